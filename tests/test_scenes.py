"""Synthetic stereo scenes: geometry, ground-truth maps, images and corners."""

from dataclasses import replace

import cv2
import numpy as np
import pytest
from scipy.ndimage import binary_dilation, map_coordinates

from ismb_lab import ParameterError, ParameterTypeError
from ismb_lab.cameras.camera import StereoCamera
from ismb_lab.scenes import (ROI, Box, Plane, Scene, Texture, cast, random_texture, render,
                             synthetic_scene, true_matches)

F, B = 300.0, 0.10


@pytest.fixture(scope="module")
def scene(rendered):
    return rendered(synthetic_scene, 0)


def wall_and_box(rig=StereoCamera.pinhole(), **kw):
    """A plain wall at 1.8 m and a 20 cm cube face at 1 m straight ahead."""
    wall = Plane((0, 0, 1.8), (1, 0, 0), (0, 1, 0), 20, 20, Texture(base=0.5))
    box = Box((-0.1, -0.1, 1.0), (0.1, 0.1, 1.2), Texture(base=0.9))
    return render([wall, box], rig, seed=0, **kw)


def random_points(rng, n, depth=(0.5, 3.0)):
    z = rng.uniform(*depth, n)
    return np.stack([rng.uniform(-0.4, 0.4, n) * z, rng.uniform(-0.3, 0.3, n) * z, z], axis=1)


def on_ray(origins, dirs, points):
    """Distance from each point to its ray (0 when the ray passes through it)."""
    return np.linalg.norm(np.cross(points - origins, dirs), axis=1)


# ---------------------------------------------------------------- projection


def test_parallel_rig_disparity_is_f_b_over_z_and_rays_invert_projection():
    rig = StereoCamera.pinhole()
    pts = random_points(np.random.default_rng(0), 200)
    left, right = rig.project_left(pts), rig.project_right(pts)
    assert np.allclose(left[:, 0] - right[:, 0], F * B / pts[:, 2], rtol=0, atol=1e-9)
    assert np.allclose(left[:, 1], right[:, 1], rtol=0, atol=1e-9)
    for rays, xy in ((rig.rays_left, left), (rig.rays_right, right)):
        o, d = rays(xy)
        assert np.allclose(np.linalg.norm(d, axis=1), 1)
        assert on_ray(o, d, pts).max() < 1e-12
    assert np.allclose(rig.rays_right(right)[0], [B, 0, 0])
    # The principal point is the image centre; points behind the camera have no image.
    assert rig.project_left([[0, 0, 1.0], [0, 0, -1.0]]).tolist()[0] == [159.5, 119.5]
    assert np.isnan(rig.project_left([[0, 0, -1.0]])).all()


def test_vertical_offset_shifts_the_right_image_down():
    pts = random_points(np.random.default_rng(1), 50)
    plain, shifted = StereoCamera.pinhole().project_right(pts), StereoCamera.pinhole(vertical_offset_px=3.5).project_right(pts)
    assert np.allclose(shifted - plain, [0, 3.5], rtol=0, atol=1e-9)
    o, d = StereoCamera.pinhole(vertical_offset_px=3.5).rays_right(shifted)
    assert on_ray(o, d, pts).max() < 1e-12


def test_roll_rotates_the_right_image_about_its_centre():
    rig = StereoCamera.pinhole(roll_deg=90)
    # On the right optical axis: the centre.  To its right in the world: above the centre.
    xy = rig.project_right([[B, 0, 1.0], [B + 0.1, 0, 1.0]])
    assert np.allclose(xy, [[159.5, 119.5], [159.5, 89.5]])
    rig = StereoCamera.pinhole(roll_deg=-7, vertical_offset_px=2)
    pts = random_points(np.random.default_rng(2), 50)
    o, d = rig.rays_right(rig.project_right(pts))
    assert on_ray(o, d, pts).max() < 1e-12
    # Roll keeps distances from the centre (for points at equal depth).
    flat = random_points(np.random.default_rng(3), 20, depth=(1.5, 1.5))
    r0 = StereoCamera.pinhole().project_right(flat) - [159.5, 119.5]
    r1 = StereoCamera.pinhole(roll_deg=30).project_right(flat) - [159.5, 119.5]
    assert np.allclose(np.hypot(*r0.T), np.hypot(*r1.T))
    assert not np.allclose(r0, r1)


@pytest.mark.parametrize("kw", [dict(), dict(roll_deg=4, vertical_offset_px=3)])
def test_correspond_lands_where_the_right_ray_hits_the_same_point(rendered, kw):
    sc = rendered(synthetic_scene, 0, **kw)
    rng = np.random.default_rng(4)
    left = rng.uniform([0, 0], [319, 239], (2000, 2))
    right = sc.correspond(left)
    seen = ~np.isnan(right[:, 0])
    assert 0.8 < seen.mean() < 1.0
    points = sc.surface_points(left)[seen]
    assert np.allclose(sc.rig.project_right(points), right[seen], rtol=0, atol=1e-9)
    o, d = sc.rig.rays_right(right[seen])
    t, _, _ = cast(sc.primitives, o, d)
    assert np.allclose(o + t[:, None] * d, points, rtol=0, atol=1e-9)
    # The unseen ones are hidden: the right ray towards their point stops earlier
    # (or the point is out of the right image).
    hidden = sc.surface_points(left)[~seen]
    xy = sc.rig.project_right(hidden)
    inside = (xy[:, 0] > -0.5) & (xy[:, 0] < 319.5) & (xy[:, 1] > -0.5) & (xy[:, 1] < 239.5)
    to_p = hidden[inside] - sc.rig.right_origin
    dist = np.linalg.norm(to_p, axis=1)
    t, _, _ = cast(sc.primitives, np.broadcast_to(sc.rig.right_origin, to_p.shape),
                   to_p / dist[:, None])
    assert np.all(t < dist - 1e-6)


def test_correspond_is_exact_geometry_not_a_map_lookup(scene):
    # Between pixel centres on the wall the disparity stays exactly f B / 1.8.
    left = np.array([[200.25, 70.75], [230.5, 75.1]])
    assert np.allclose(left[:, 0] - scene.correspond(left)[:, 0], F * B / 1.8, rtol=0, atol=1e-9)
    assert scene.correspond(np.zeros((0, 2))).shape == (0, 2)


# ------------------------------------------------------------ ground truth


def test_wall_and_box_maps_are_exact_and_the_occluded_strip_is_where_expected():
    sc = wall_and_box(noise_std=0)
    wall = np.abs(sc.depth - 1.8) < 1e-12
    box = np.abs(sc.depth - 1.0) < 1e-12
    assert wall.sum() + box.sum() == sc.depth.size
    assert np.all(np.abs(sc.disparity[wall & ~sc.occluded] - F * B / 1.8) < 1e-9)
    assert np.all(np.abs(sc.disparity[box] - 30.0) < 1e-9)
    assert np.all(np.isnan(sc.disparity) == sc.occluded)
    # The box (columns 129.5..189.5) hides the wall from the right camera on its
    # left side: wall columns u >= 159.5 - 0.26 * 300 / 1.8 = 116.17.
    row = sc.occluded[119]
    assert row[117:130].all() and not row[116] and not row[130:].any()
    assert box[119, 130:190].all() and not box[119, 129]
    # Left of column 16.17 the wall is out of the right image.
    assert sc.occluded[:, :17].all() and not sc.occluded[:60, 17:].any()


def test_synthetic_scene_maps(scene):
    wall_d = F * B / 1.8
    seen = ~scene.occluded
    on_wall = np.isclose(scene.depth, 1.8)
    assert np.all(np.abs(scene.disparity[on_wall & seen] - wall_d) < 1e-9)
    # Parallel rig: disparity is f B / z everywhere it is defined.
    assert np.allclose(scene.disparity[seen], F * B / scene.depth[seen], rtol=0, atol=1e-9)
    assert np.all(np.isnan(scene.disparity) == scene.occluded)
    # Boxes at 1.0-1.3 m in the ROI: larger disparities than the wall.
    x, y, w, h = ROI
    roi_d = scene.disparity[y:y + h, x:x + w]
    boxes = (scene.depth[y:y + h, x:x + w] < 1.45) & (np.arange(h)[:, None] < 140 - y)
    assert boxes.sum() > 1000 and np.all(roi_d[boxes & ~np.isnan(roi_d)] > wall_d + 3)
    # Occluded wall pixels sit immediately left of the boxes' silhouettes.
    occ = scene.occluded[y:y + h, x:x + w]
    assert occ.sum() > 100
    rows, cols = np.nonzero(occ & (scene.depth[y:y + h, x:x + w] > 1.7))
    assert np.all(cols < w - 1)
    right_of = scene.depth[y:y + h, x:x + w][rows, cols + 1]
    assert np.mean(right_of < 1.45) > 0.05 and np.all(occ[rows, cols + 1] | (right_of < 1.45))


def test_no_poster_is_cut_by_a_box_silhouette(scene):
    # The wall behind the boxes, as seen from either camera, is bare: no corner
    # of the scene is an occlusion junction that moves between the views.
    wall, table, *boxes = scene.primitives
    assert isinstance(wall, Plane) and isinstance(table, Plane) and 1 <= len(boxes) <= 2
    bare = replace(wall.texture, rects=np.full((0, 0, 4), np.nan), levels=np.zeros((0, 0)))
    gy, gx = np.mgrid[0:240, 0:320]
    xy = np.stack([gx.ravel(), gy.ravel()], axis=1).astype(float)
    for rays in (scene.rig.rays_left, scene.rig.rays_right):
        o, d = rays(xy)
        _, which, _ = cast(scene.primitives, o, d)
        behind = which >= 2
        assert behind.sum() > 2000
        _, info = wall.intersect(o[behind], d[behind])
        assert np.array_equal(wall.texture(info[:, :2]), bare(info[:, :2]))
    # ... while the wall elsewhere has posters.
    _, info = wall.intersect(*scene.rig.rays_left(xy))
    assert np.mean(wall.texture(info[:, :2]) != bare(info[:, :2])) > 0.05


# ------------------------------------------------------------------ images


def smooth_pixels(sc, margin=3, spread=12):
    """Visible left pixels far from depth edges, borders and texture edges."""
    occ = sc.occluded | ~np.isfinite(sc.depth)
    edge = np.zeros_like(occ)
    edge[:, 1:] |= np.abs(np.diff(sc.depth, axis=1)) > 0.05
    edge[1:] |= np.abs(np.diff(sc.depth, axis=0)) > 0.05
    kernel = np.ones((2 * margin + 1, 2 * margin + 1), bool)
    near_edge = binary_dilation(occ | edge, kernel)
    square = kernel.astype(np.uint8)
    flat = cv2.dilate(sc.left, square) - cv2.erode(sc.left, square) < spread
    ok = ~near_edge & flat
    border = margin + 20
    ok[:border], ok[-border:], ok[:, :border], ok[:, -border:] = False, False, False, False
    return np.argwhere(ok)[:, ::-1].astype(float)


def residual(sc, left_xy, shift=(0.0, 0.0)):
    """|left - right| at true correspondences, right brought back through its gain and offset."""
    right_xy = sc.correspond(left_xy) + shift
    right = (sc.right - sc.offset) / sc.gain
    value = map_coordinates(right, [right_xy[:, 1], right_xy[:, 0]], order=1)
    return np.abs(value - sc.left[left_xy[:, 1].astype(int), left_xy[:, 0].astype(int)])


@pytest.mark.parametrize("kw", [dict(), dict(roll_deg=-3, vertical_offset_px=2.5)])
def test_right_image_at_the_correspondence_matches_the_left_pixel(rendered, kw):
    sc = rendered(synthetic_scene, 1, **kw)
    assert (sc.gain, sc.offset, sc.noise_std) == (0.9, 8.0, 1.0)
    pts = smooth_pixels(sc)
    pts = pts[np.random.default_rng(5).choice(len(pts), 3000, replace=False)]
    err = residual(sc, pts)
    # Noise 1 in each view plus 8-bit quantisation: about 1.5 grey levels.
    assert np.median(err) < 1.5 and np.percentile(err, 99) < 5.0
    # A wrong geometry (here the rig without roll/offset, or no rig at all) does not fit.
    if kw:
        plain = rendered(synthetic_scene, 1)
        assert np.percentile(np.abs(plain.correspond(pts) - sc.correspond(pts)), 50) > 1
    assert residual(sc, pts, shift=(12.0, 0.0)).mean() > 3 * err.mean()


def test_correspondence_is_sharp_on_textured_pixels(scene):
    # All visible pixels away from depth edges, texture edges included.
    pts = smooth_pixels(scene, margin=2, spread=np.inf)
    exact = residual(scene, pts).mean()
    assert exact < 2.0
    for shift in [(1.0, 0.0), (-1.0, 0.0), (0.0, 1.0), (0.0, -1.0)]:
        assert residual(scene, pts, shift).mean() > exact + 0.4


@pytest.mark.slow
def test_images_are_float_grey_levels_and_the_right_camera_differs(scene):
    for img in (scene.left, scene.right):
        assert img.dtype == np.float64 and img.shape == (240, 320)
        assert img.min() >= 0 and img.max() <= 255 and np.all(img == np.rint(img))
        assert img.std() > 20
    assert not scene.left.flags.writeable
    plain = render(scene.primitives, scene.rig, seed=0, noise_std=0, quantise=False)
    bright = render(scene.primitives, scene.rig, seed=0, noise_std=0, gain=1.2, offset=-5,
                    quantise=False)
    assert np.array_equal(plain.left, bright.left)
    assert np.allclose(bright.right, np.clip(1.2 * plain.right - 5, 0, 255))


@pytest.mark.slow
def test_supersampling_antialiases_edges_only():
    wall = Plane((0, 0, 1.8), (1, 0, 0), (0, 1, 0), 20, 20, Texture(base=0.5))
    # The box's left edge is at column 129.75: pixel 130 is 3/4 box, 1/4 wall.
    box = Box(((129.75 - 159.5) / F, -0.1, 1.0), (0.1, 0.1, 1.2), Texture(base=0.9))
    one, four = (render([wall, box], seed=0, noise_std=0, supersample=s, quantise=False)
                 for s in (1, 4))
    w, b = four.left[119, 120], four.left[119, 140]
    assert one.left[119, 130] == b
    assert four.left[119, 130] == pytest.approx(0.25 * w + 0.75 * b)
    assert np.array_equal(one.left[100:140, 135:180], four.left[100:140, 135:180])


# --------------------------------------------------------------- determinism


@pytest.mark.slow
def test_same_seed_same_images_different_seed_different():
    a, b, c = synthetic_scene(7), synthetic_scene(7), synthetic_scene(8)
    for name in ("left", "right", "depth", "disparity", "occluded"):
        assert np.array_equal(getattr(a, name), getattr(b, name), equal_nan=name != "occluded")
    assert not np.array_equal(a.left, c.left) and not np.array_equal(a.right, c.right)
    # render's seed drives the noise only.
    n1 = render(a.primitives, a.rig, seed=1)
    n2 = render(a.primitives, a.rig, seed=2)
    assert np.array_equal(n1.left, render(a.primitives, a.rig, seed=1).left)
    assert not np.array_equal(n1.left, n2.left)
    assert np.array_equal(n1.disparity, n2.disparity, equal_nan=True)
    assert np.abs(n1.left - n2.left).mean() < 2
    # A Generator works as well as an integer seed.
    assert np.array_equal(synthetic_scene(np.random.default_rng(7)).left, a.left)


def test_random_texture_is_deterministic_and_corner_rich():
    t1 = random_texture(3, (0, 0, 1, 1), cell=0.2)
    t2 = random_texture(np.random.default_rng(3), (0, 0, 1, 1), cell=0.2)
    uv = np.random.default_rng(0).uniform(0, 1, (1000, 2))
    assert np.array_equal(t1(uv), t2(uv))
    assert not np.array_equal(t1(uv), random_texture(4, (0, 0, 1, 1), cell=0.2)(uv))
    assert 0 < np.isnan(t1.rects[..., 0]).sum() < t1.rects[..., 0].size
    assert np.all((t1(uv) >= 0) & (t1(uv) <= 1))


def test_box_faces_are_textured_and_shaded_differently():
    box = Box((-0.1, -0.1, 1.0), (0.1, 0.1, 1.2), [Texture(base=0.1 * (i + 2)) for i in range(6)])
    # Rays into the -x, -y and -z faces.
    o = np.array([[-1.0, 0, 1.1], [0, -1.0, 1.1], [0, 0, 0]])
    d = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0]])
    t, info = box.intersect(o, d)
    assert np.allclose(t, [0.9, 0.9, 1.0]) and info[:, 2].tolist() == [0, 2, 4]
    assert np.allclose(box.albedo(info), [0.2, 0.4, 0.6])
    assert np.allclose(box.normals(info), -d)
    # Lambertian shading under the default light (0.3, -0.8, -1) with ambient 0.35:
    # a uniform box's front (-z) and side (+x) faces differ in brightness.
    rig = StereoCamera.pinhole(width=64, height=48, focal_px=60)
    cube = Box((-0.5, -0.2, 0.8), (-0.1, 0.2, 1.4), Texture(base=0.8))
    sc = render([cube], rig, seed=0, noise_std=0, supersample=1, quantise=False)
    gy, gx = np.mgrid[0:48, 0:64]
    _, which, info = cast([cube], *rig.rays_left(np.stack([gx.ravel(), gy.ravel()], 1) * 1.0))
    face = np.where(which >= 0, info[:, 2], -1).reshape(48, 64)
    light = np.array([0.3, -0.8, -1.0]) / np.linalg.norm([0.3, -0.8, -1.0])
    for f, normal in ((4, [0, 0, -1]), (1, [1, 0, 0])):
        assert (face == f).sum() >= 10
        expected = 255 * 0.8 * (0.35 + 0.65 * max(0.0, float(np.dot(normal, light))))
        assert np.allclose(sc.left[face == f], expected)
    assert sc.left[face == 4].mean() - sc.left[face == 1].mean() > 50
    assert np.all(sc.left[face == -1] == 0)    # background


# ------------------------------------------------------------------ corners


def harris(img, roi):
    x, y, w, h = roi
    mask = np.zeros(img.shape, np.uint8)
    mask[max(y, 0):y + h, max(x, 0):x + w] = 1
    c = cv2.goodFeaturesToTrack(img.astype(np.float32), 200, 0.05, 8, mask=mask, blockSize=5,
                                useHarrisDetector=True, k=0.04)
    return np.zeros((0, 2)) if c is None else c.reshape(-1, 2)


@pytest.mark.parametrize("seed, kw", [(0, {}), (1, {}), (2, {}), (3, {}),
                                      (0, dict(roll_deg=3, vertical_offset_px=4))])
def test_harris_corners_in_the_roi_have_true_partners(rendered, seed, kw):
    sc = rendered(synthetic_scene, seed, **kw)
    x, y, w, h = ROI
    left = harris(sc.left, ROI)
    right = harris(sc.right, ROI)
    assert len(left) >= 20 and len(right) >= 20
    assert len(left) <= 50
    # Partners lie up to ~30 px to the left: look for them in the ROI widened by 40 px.
    right = harris(sc.right, (x - 40, y - 8, w + 40, h + 16))
    partner = true_matches(sc, left, right, tol=1.5)
    assert np.mean(partner >= 0) >= 0.8
    # Corners lie on the wall and on the boxes.
    depth = sc.depth[np.rint(left[:, 1]).astype(int), np.rint(left[:, 0]).astype(int)]
    assert np.sum(depth > 1.7) >= 4 and np.sum(depth < 1.45) >= 4


def test_true_matches_picks_the_nearest_partner_within_tol(scene):
    left = np.array([[200.0, 70.0], [0.0, 100.0], [210.0, 80.0], [205.0, 75.0]])
    truth = scene.correspond(left)
    right = np.array([truth[0] + [1.0, 0.5], truth[0] + [0.2, 0], truth[2] + [1.6, 0], [50, 50]])
    assert true_matches(scene, left, right).tolist() == [1, -1, -1, -1]
    assert true_matches(scene, left, right, tol=2.0).tolist() == [1, -1, 2, -1]
    assert true_matches(scene, left, np.zeros((0, 2))).tolist() == [-1] * 4
    assert true_matches(scene, np.zeros((0, 2)), right).shape == (0,)


# ---------------------------------------------------------------- validation


@pytest.mark.parametrize("make, name, error", [
    (lambda: StereoCamera.pinhole(focal_px=-300), "focal_px", ValueError),
    (lambda: StereoCamera.pinhole(focal_px=0), "focal_px", ValueError),
    (lambda: StereoCamera.pinhole(baseline_m=-0.1), "baseline_m", ValueError),
    (lambda: StereoCamera.pinhole(width=0), "width", ValueError),
    (lambda: StereoCamera.pinhole(height=1), "height", ValueError),
    (lambda: StereoCamera.pinhole(width=320.5), "width", TypeError),
    (lambda: StereoCamera.pinhole(roll_deg=float("nan")), "roll_deg", ValueError),
    (lambda: StereoCamera.pinhole(vertical_offset_px="2"), "vertical_offset_px", TypeError),
    (lambda: StereoCamera.pinhole().project_left([[1.0, 2.0]]), "points3d", ValueError),
    (lambda: StereoCamera.pinhole().rays_right([[1.0, np.nan]]), "xy", ValueError),
    (lambda: Plane((0, 0, 1), (1, 0, 0), (1, 1, 0), 1, 1, Texture()), "v_axis", ValueError),
    (lambda: Plane((0, 0, 1), (1, 0, 0), (0, 1, 0), -1, 1, Texture()), "half_u", ValueError),
    (lambda: Plane((0, 0), (1, 0, 0), (0, 1, 0), 1, 1, Texture()), "centre", ValueError),
    (lambda: Plane((0, 0, 1), (1, 0, 0), (0, 1, 0), 1, 1, 0.5), "texture", TypeError),
    (lambda: Box((0, 0, 1), (1, 1, 1), Texture()), "hi", ValueError),
    (lambda: Box((0, 0, 1), (1, 1, 2), [Texture()] * 5), "textures", ValueError),
    (lambda: Texture(base=1.5), "base", ValueError),
    (lambda: Texture(rects=np.zeros((2, 2, 4)), levels=np.zeros((2, 3))), "levels", ValueError),
    (lambda: random_texture(0, (0, 0, -1, 1), cell=0.1), "extent", ValueError),
    (lambda: random_texture(0, (0, 0, 1, 1), cell=0), "cell", ValueError),
    (lambda: render([], seed=0), "primitives", TypeError),
    (lambda: render([Texture()], seed=0), "primitives", TypeError),
    (lambda: wall_and_box(supersample=0), "supersample", ValueError),
    (lambda: wall_and_box(noise_std=-1), "noise_std", ValueError),
    (lambda: wall_and_box(gain=0), "gain", ValueError),
    (lambda: wall_and_box(light=(0, 0, 0)), "light", ValueError),
    (lambda: render([Box((0, 0, 1), (1, 1, 2), Texture())], StereoCamera.pinhole(), seed=-1), "seed", ValueError),
    (lambda: render([Box((0, 0, 1), (1, 1, 2), Texture())], "rig", seed=0), "rig", TypeError),
    (lambda: synthetic_scene(0, roll_deg=400), "roll_deg", ValueError),
    (lambda: synthetic_scene(0, noise_std=-2), "noise_std", ValueError),
    (lambda: synthetic_scene(1.5), "seed", TypeError),
])
def test_bad_arguments_name_the_parameter(make, name, error):
    error = {ValueError: ParameterError, TypeError: ParameterTypeError}[error]
    with pytest.raises(error, match=rf"^The '{name}' parameter of \w[\w.]* must be .* Got .* instead\.$"):
        make()


def test_scene_and_true_matches_validate(scene):
    with pytest.raises(ValueError, match="The 'left' parameter of Scene must be an array of shape"):
        Scene(np.zeros((10, 10)), scene.right, scene.depth, scene.disparity, scene.occluded,
              scene.rig, scene.primitives)
    with pytest.raises(ValueError, match="The 'tol' parameter of true_matches"):
        true_matches(scene, [[1, 2]], [[1, 2]], tol=0)
    with pytest.raises(TypeError, match="The 'scene' parameter of true_matches must be a Scene"):
        true_matches(None, [[1, 2]], [[1, 2]])
    with pytest.raises(ValueError, match="The 'left_xy' parameter of Scene.correspond"):
        scene.correspond([[1, 2, 3]])


# ------------------------------------------------------------ depth-demo scenes

from ismb_lab.scenes import (CAR_DEPTH, REALISTIC_COUNT, Group, lab_scene, realistic_scene,  # noqa: E402
                             toy_car, toy_car_layout, toy_car_scene)


def test_toy_car_scene_is_the_lab_scene_plus_two_cars_left_nearer():
    lab, cars = lab_scene(0, supersample=1), toy_car_scene(0, supersample=1)
    wall, table, box = lab.primitives
    assert len(cars.primitives) == 5
    for a, b in zip(lab.primitives, cars.primitives[:3]):
        assert type(a) is type(b)
    assert np.array_equal(box.lo, cars.primitives[2].lo) and np.array_equal(box.hi, cars.primitives[2].hi)
    left, right = cars.primitives[3:]
    assert isinstance(left, Group) and (left.name, right.name) == ("left car", "right car")
    assert left.parts[0].lo[2] < right.parts[0].lo[2] and right.hi[2] < box.lo[2]
    # Where no car is, both views see the same surfaces: disparity maps agree.
    free = np.isfinite(lab.disparity) & np.isfinite(cars.disparity) & (cars.depth == lab.depth)
    assert free.mean() > 0.85
    assert np.allclose(lab.disparity[free], cars.disparity[free])
    # The cars are seen at their own depth (body side or wheels), left of and right of the box.
    cx = lambda car: float(np.mean(cars.rig.project_left([(car.lo + car.hi) / 2])[0, 0]))
    x_box = cars.rig.project_left([(box.lo + box.hi) / 2])[0, 0]
    assert cx(left) < x_box < cx(right)
    for car in (left, right):
        z = car.parts[0].lo[2]
        seen = np.isclose(cars.depth, z) | np.isclose(cars.depth, z - 0.006)
        assert seen.sum() > 300


def test_car_variants_differ_and_stay_in_their_ranges():
    layouts = {toy_car_layout(c) for c in range(30)}
    assert len(layouts) == 30
    for (xl, zl, ll), (xr, zr, lr) in layouts:
        assert 0.88 <= zl and zl + 0.1 <= zr <= 1.2 and xl < xr
        assert 0.09 <= ll <= 0.11 and 0.09 <= lr <= 0.11
    a, b = toy_car_scene(0, cars=1, supersample=1), toy_car_scene(0, cars=2, supersample=1)
    assert not np.array_equal(a.left, b.left)


def test_group_normals_and_albedo_follow_the_part_hit():
    car = toy_car(3, 0.0, 1.0)
    o = np.zeros((2, 3))
    d = np.array([[0.0, 0.11, 1.0], [0.0, -1.0, 0.0]])
    d /= np.linalg.norm(d, axis=1)[:, None]
    t, info = car.intersect(o, d)
    assert np.isclose(t[0] * d[0, 2], 1.0) and np.isinf(t[1])
    assert info[0, 2] == 4                      # the body's front face, part 0
    assert car.normals(info[:1]).tolist() == [[0, 0, -1]]
    assert car.hi[2] == pytest.approx(1.0 + CAR_DEPTH + 0.006)


@pytest.mark.slow
def test_realistic_scenes_vary_and_some_are_not_rectified():
    rigs = [realistic_scene(n, supersample=1).rig for n in range(1, REALISTIC_COUNT + 1)]
    offsets = [r.vertical_offset_px for r in rigs]
    assert sum(o > 0 for o in offsets) >= 5 and all(o == 0 or 2.5 <= o <= 5 for o in offsets)
    assert any(r.roll_deg != 0 for r in rigs)
    a, b = realistic_scene(1, supersample=1), realistic_scene(1, supersample=1)
    assert np.array_equal(a.left, b.left)


@pytest.mark.parametrize("make, name, error", [
    (lambda: toy_car(0, 0.0, -1.0), "z_front", ValueError),
    (lambda: toy_car(0, 0.0, 1.0, length=2.0), "length", ValueError),
    (lambda: Group([]), "parts", TypeError),
    (lambda: Group([Texture()]), "parts", TypeError),
    (lambda: lab_scene(0, noise_std=-1), "noise_std", ValueError),
    (lambda: toy_car_scene(0, cars=-3), "cars", ValueError),
    (lambda: toy_car_layout(0, rig="rig"), "rig", TypeError),
    (lambda: realistic_scene(0), "index", ValueError),
    (lambda: realistic_scene(1.5), "index", TypeError),
])
def test_demo_scene_arguments_are_checked(make, name, error):
    error = {ValueError: ParameterError, TypeError: ParameterTypeError}[error]
    with pytest.raises(error, match=rf"^The '{name}' parameter of \w[\w.]* must be .* Got .* instead\.$"):
        make()
