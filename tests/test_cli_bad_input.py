"""A sweep of bad inputs across every command: one line on stderr, exit 2, no input changed.

Each case runs ``main()`` in a folder of real inputs (images/lab's pair and answer key)
and hostile ones (a FIFO, a character device, a read-only file, links, JSON nested
100 000 deep, a 20000 x 20000 PNG of 390 KB).  Before and after every case the sha256
of every file, the kind and mode of every entry and the target of every link are
compared.
"""

import json
import os
import shutil
import stat
import zlib
from pathlib import Path

import pytest

from ismb_lab.cli import main

IMAGES = Path(__file__).resolve().parent.parent / "images"


def big_png(path, width, height):
    """A valid grey 8-bit PNG of width x height zero pixels, compressed as a stream (small file)."""
    def chunk(kind, data):
        return (len(data).to_bytes(4, "big") + kind + data
                + zlib.crc32(kind + data).to_bytes(4, "big"))

    compressor = zlib.compressobj(9)
    row = bytes(width + 1)   # filter byte 0, then the row
    body = b"".join(compressor.compress(row) for _ in range(height)) + compressor.flush()
    ihdr = width.to_bytes(4, "big") + height.to_bytes(4, "big") + bytes([8, 0, 0, 0, 0])
    Path(path).write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", body)
                           + chunk(b"IEND", b""))
    return Path(path)


def make_workspace(folder: Path, huge: bool = True) -> Path:
    """images/lab's pair and answer key, plus the bad files the sweep uses."""
    folder.mkdir(parents=True, exist_ok=True)
    for name, target in (("left.png", "L.png"), ("right.png", "R.png"), ("answer_key.json", "targets.json")):
        shutil.copy(IMAGES / "lab" / name, folder / target)
    (folder / "params.json").write_text(json.dumps({"method": "III", "params": {"theta_c": 17.0}}))
    (folder / "nm4_bias.json").write_text(json.dumps({"method": "NM4", "params": {"match_bias": 5}}))
    deep = "[" * 100_000 + "]" * 100_000
    (folder / "deep.json").write_text(deep)
    (folder / "deep_params.json").write_text('{"params": ' + deep + "}")
    entry = {"name": "lab", "left": "L.png", "right": "R.png", "targets": "targets.json"}
    (folder / "manifest.json").write_text(json.dumps({"pairs": [entry, {**entry, "name": "again"}]}))
    (folder / "manifest_int_path.json").write_text(json.dumps({"pairs": [{**entry, "left": 5}]}))
    (folder / "manifest_deep.json").write_text('{"pairs": ' + deep + "}")
    other = json.loads((folder / "targets.json").read_text())
    other["left_image_sha256"] = "0" * 64
    (folder / "targets_other_images.json").write_text(json.dumps(other))
    (folder / "text.png").write_text("not an image")
    ro = folder / "readonly.json"
    ro.write_text("{}\n")
    ro.chmod(0o444)
    shutil.copy(folder / "L.png", folder / "readonly.png")
    (folder / "readonly.png").chmod(0o444)
    (folder / "existing.json").write_text('{"keep": true}\n')
    os.mkfifo(folder / "fifo")
    os.mkfifo(folder / "fifo_out.json")
    try:   # a private /dev/null: a character device the tests may safely see replaced
        os.mknod(folder / "null_device", stat.S_IFCHR | 0o666, os.makedev(1, 3))
    except (PermissionError, OSError):
        pass
    (folder / "link_to_L.png").symlink_to(folder / "L.png")
    (folder / "dir_link").symlink_to(folder)
    (folder / "sub").mkdir()
    if huge:
        big_png(folder / "huge.png", 20000, 20000)
    make_issue25_inputs(folder)
    return folder


def make_issue25_inputs(folder: Path) -> None:
    """Empty and header-only images, numbers of 400 digits, degenerate rigs, render's output
    folders with a link, a FIFO and a read-only file, and oversized targets files."""
    (folder / "empty.png").write_bytes(b"")
    (folder / "huge.hdr").write_bytes(b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 12000 +X 12000\n")
    huge = int("9" * 400)
    targets = json.loads((folder / "targets.json").read_text())
    targets["pairs"][0]["left_xy"][0] = huge
    (folder / "targets_400_digits.json").write_text(json.dumps(targets))
    (folder / "params_400_digits.json").write_text(json.dumps({"method": "III", "params": {"theta_c": huge}}))
    pairs = [{"left_xy": [n % 300, n // 300], "right_xy": [n % 300, n // 300]} for n in range(10_001)]
    (folder / "targets_many_pairs.json").write_text(json.dumps({"version": 1, "pairs": pairs}))
    (folder / "targets_5mb.json").write_text(json.dumps(targets) + " " * (5 << 20))
    rig = {"format": "ismb_lab-rig-v1", "size": [320, 240], "rms_px": 0.3, "board": [9, 6], "square_m": 0.025,
           "k_left": [[300, 0, 160], [0, 300, 120], [0, 0, 1]], "d_left": [0, 0, 0, 0, 0],
           "k_right": [[300, 0, 160], [0, 300, 120], [0, 0, 1]], "d_right": [0, 0, 0, 0, 0],
           "rotation": [[1, 0, 0], [0, 1, 0], [0, 0, 1]], "translation": [-0.1, 0, 0]}
    zero = [[0, 0, 0]] * 3
    for name, change in (("zero_k", {"k_left": zero, "k_right": zero}), ("nan_d", {"d_left": [float("nan")] * 5}),
                         ("zero_baseline", {"translation": [0, 0, 0]}), ("400_digits", {"size": [huge, 240]})):
        (folder / f"rig_{name}.json").write_text(json.dumps({**rig, **change}))
    for kind in ("link", "fifo", "readonly", "folder_link"):
        (folder / f"render_{kind}" / "lab").mkdir(parents=True)
    (folder / "render_link" / "lab" / "left.png").symlink_to(folder / "existing.json")
    os.mkfifo(folder / "render_fifo" / "lab" / "left.png")
    shutil.copy(folder / "L.png", folder / "render_readonly" / "lab" / "left.png")
    (folder / "render_readonly" / "lab" / "left.png").chmod(0o444)
    (folder / "render_folder_link" / "toy_cars").symlink_to(folder / "sub")


def snapshot(folder: Path) -> dict:
    """sha256 of every regular file, the kind and mode of every entry, and every link's target."""
    import hashlib

    state = {}
    paths = [Path(root) / name for root, dirs, files in os.walk(folder) for name in dirs + files]
    for path in sorted(paths):
        st = os.lstat(path)
        key = str(path.relative_to(folder))
        if stat.S_ISLNK(st.st_mode):
            state[key] = ("link", os.readlink(path))
        elif stat.S_ISREG(st.st_mode):
            state[key] = ("file", oct(st.st_mode), hashlib.sha256(path.read_bytes()).hexdigest())
        else:
            state[key] = ("other", oct(st.st_mode), st.st_rdev)
    return state


@pytest.fixture(scope="module")
def ws(tmp_path_factory):
    return make_workspace(tmp_path_factory.mktemp("bad_inputs"))


def _pair(w):
    return [w / "L.png", w / "R.png"]


def _tune(w, *more):
    return ["tune", *_pair(w), w / "targets.json", *more]


def _depth(w, *more):
    return ["depth", *_pair(w), *_pair(w), *more]


# (id, arguments from the folder, words the one line must hold, extra environment)
CASES = [
    # match: outputs
    ("match-json-is-left", lambda w: ["match", *_pair(w), "--json", w / "L.png"], "also an input", {}),
    ("match-plot-is-right", lambda w: ["match", *_pair(w), "--plot", w / "R.png"], "also an input", {}),
    ("match-json-link-to-input", lambda w: ["match", *_pair(w), "--json", w / "link_to_L.png"],
     "also an input", {}),
    ("match-json-input-other-spelling", lambda w: ["match", *_pair(w), "--json", w / "sub" / ".." / "R.png"],
     "also an input", {}),
    ("match-json-is-params-file", lambda w: ["match", *_pair(w), "--params-file", w / "params.json",
                                             "--json", w / "params.json"], "also an input", {}),
    ("match-json-fifo", lambda w: ["match", *_pair(w), "--json", w / "fifo_out.json"], "FIFO", {}),
    ("match-json-device", lambda w: ["match", *_pair(w), "--json", w / "null_device"], "device", {}),
    ("match-json-readonly", lambda w: ["match", *_pair(w), "--json", w / "readonly.json"], "read-only", {}),
    ("match-json-no-folder", lambda w: ["match", *_pair(w), "--json", w / "nodir" / "m.json"],
     "does not exist", {}),
    ("match-json-folder", lambda w: ["match", *_pair(w), "--json", w / "sub"], "folder", {}),
    ("match-json-link-to-folder", lambda w: ["match", *_pair(w), "--json", w / "dir_link"], "folder", {}),
    ("match-json-under-a-file", lambda w: ["match", *_pair(w), "--json", w / "existing.json" / "m.json"],
     "Not a directory", {}),
    ("match-plot-unknown-format", lambda w: ["match", *_pair(w), "--plot", w / "out.xyz"], "cannot draw", {}),
    ("match-json-and-plot-same", lambda w: ["match", *_pair(w), "--json", w / "o.png", "--plot", w / "o.png"],
     "same file", {}),
    # match: inputs
    ("match-left-fifo", lambda w: ["match", w / "fifo", w / "R.png"], "FIFO", {}),
    ("match-left-device", lambda w: ["match", w / "null_device", w / "R.png"], "device", {}),
    ("match-left-folder", lambda w: ["match", w / "sub", w / "R.png"], "folder", {}),
    ("match-left-text", lambda w: ["match", w / "text.png", w / "R.png"], "not an image file", {}),
    ("match-left-huge-png", lambda w: ["match", w / "huge.png", w / "R.png"], "ISMB_LAB_MAX_PIXELS", {}),
    ("match-params-fifo", lambda w: ["match", *_pair(w), "--params-file", w / "fifo"], "FIFO", {}),
    ("match-params-dev-zero", lambda w: ["match", *_pair(w), "--params-file", "/dev/zero"], "device", {}),
    ("match-params-deep", lambda w: ["match", *_pair(w), "--params-file", w / "deep_params.json"],
     "nested too deeply", {}),
    ("match-params-nm4-bias", lambda w: ["match", *_pair(w), "--params-file", w / "nm4_bias.json"],
     "match_bias", {}),
    ("match-nm4-bias-option", lambda w: ["match", *_pair(w), "--method", "NM4", "--match-bias", "5"],
     "match_bias", {}),
    ("match-iii-bias-option", lambda w: ["match", *_pair(w), "--match-bias", "1"], "match_bias", {}),
    ("match-nm3-theta-s-option", lambda w: ["match", *_pair(w), "--method", "NM3", "--theta-s", "5"],
     "theta_s", {}),
    ("match-n-max-limit", lambda w: ["match", *_pair(w), "--n-max", "5000"], "ISMB_LAB_MAX_CORNERS", {}),
    ("match-bad-pixel-limit", lambda w: ["match", *_pair(w)], "ISMB_LAB_MAX_PIXELS",
     {"ISMB_LAB_MAX_PIXELS": "many"}),
    ("match-lowered-pixel-limit", lambda w: ["match", *_pair(w)], "ISMB_LAB_MAX_PIXELS",
     {"ISMB_LAB_MAX_PIXELS": "1000"}),
    # tune
    ("tune-out-is-targets", lambda w: _tune(w, "--out", w / "targets.json"), "also an input", {}),
    ("tune-out-is-left", lambda w: _tune(w, "--out", w / "L.png"), "also an input", {}),
    ("tune-out-no-folder", lambda w: _tune(w, "--out", w / "nodir" / "p.json"), "nodir/p.json", {}),
    ("tune-out-fifo", lambda w: _tune(w, "--out", w / "fifo_out.json"), "FIFO", {}),
    ("tune-out-readonly", lambda w: _tune(w, "--out", w / "readonly.json"), "read-only", {}),
    ("tune-population-limit", lambda w: _tune(w, "--population", "100000000"), "ISMB_LAB_MAX_POPULATION", {}),
    ("tune-generations-limit", lambda w: _tune(w, "--generations", "1000000"), "ISMB_LAB_MAX_GENERATIONS", {}),
    ("tune-n-max-limit", lambda w: _tune(w, "--n-max", "5000"), "ISMB_LAB_MAX_CORNERS", {}),
    ("tune-targets-fifo", lambda w: ["tune", *_pair(w), w / "fifo"], "FIFO", {}),
    ("tune-targets-dev-zero", lambda w: ["tune", *_pair(w), "/dev/zero"], "device", {}),
    ("tune-targets-deep", lambda w: ["tune", *_pair(w), w / "deep.json"], "targets '", {}),
    ("tune-targets-other-images", lambda w: ["tune", *_pair(w), w / "targets_other_images.json"],
     "--no-hash-check", {}),
    ("tune-right-huge-png", lambda w: ["tune", w / "L.png", w / "huge.png", w / "targets.json"],
     "ISMB_LAB_MAX_PIXELS", {}),
    # evaluate
    ("evaluate-json-is-manifest", lambda w: ["evaluate", w / "manifest.json", "--json", w / "manifest.json"],
     "also an input", {}),
    ("evaluate-json-is-a-listed-image", lambda w: ["evaluate", w / "manifest.json", "--json", w / "L.png"],
     "also an input", {}),
    ("evaluate-json-is-listed-targets", lambda w: ["evaluate", w / "manifest.json", "--json",
                                                   w / "targets.json"], "also an input", {}),
    ("evaluate-json-device", lambda w: ["evaluate", w / "manifest.json", "--json", w / "null_device"],
     "device", {}),
    ("evaluate-manifest-fifo", lambda w: ["evaluate", w / "fifo"], "FIFO", {}),
    ("evaluate-manifest-int-path", lambda w: ["evaluate", w / "manifest_int_path.json"], "a string", {}),
    ("evaluate-manifest-deep", lambda w: ["evaluate", w / "manifest_deep.json"], "nested too deeply", {}),
    ("evaluate-generations-limit", lambda w: ["evaluate", w / "manifest.json", "--generations", "1000000"],
     "ISMB_LAB_MAX_GENERATIONS", {}),
    ("evaluate-seeds-limit", lambda w: ["evaluate", w / "manifest.json", "--seeds", "1000"],
     "ISMB_LAB_MAX_SEEDS", {}),
    # depth
    ("depth-json-is-input", lambda w: _depth(w, "--json", w / "L.png"), "also an input", {}),
    ("depth-plot-unknown-format", lambda w: _depth(w, "--plot", w / "d.xyz"), "cannot draw", {}),
    ("depth-plot-readonly", lambda w: _depth(w, "--plot", w / "readonly.png"), "read-only", {}),
    ("depth-json-device", lambda w: _depth(w, "--json", w / "null_device"), "device", {}),
    ("depth-scene-fifo", lambda w: ["depth", *_pair(w), w / "fifo", w / "R.png"], "FIFO", {}),
    ("depth-params-deep", lambda w: _depth(w, "--params-file", w / "deep_params.json"),
     "nested too deeply", {}),
    ("depth-n-max-limit", lambda w: _depth(w, "--n-max", "5000"), "ISMB_LAB_MAX_CORNERS", {}),
    # render
    ("render-out-is-a-file", lambda w: ["render", "--out", w / "existing.json"], "not a folder", {}),
    # issue 25: empty images, in every command that reads one
    ("match-left-empty", lambda w: ["match", w / "empty.png", w / "R.png"], "the file is empty", {}),
    ("tune-right-empty", lambda w: ["tune", w / "L.png", w / "empty.png", w / "targets.json"],
     "the file is empty", {}),
    ("depth-scene-empty", lambda w: ["depth", *_pair(w), w / "empty.png", w / "R.png"], "the file is empty", {}),
    ("rectify-left-empty", lambda w: ["rectify", w / "empty.png", w / "R.png", "--out", w / "rect"],
     "the file is empty", {}),
    ("calibrate-photo-empty", lambda w: ["calibrate", *[w / "empty.png", w / "R.png"] * 3, "--out", w / "rig.json"],
     "the file is empty", {}),
    # a header that declares 12000 x 12000 pixels: refused before decoding
    ("match-left-huge-hdr", lambda w: ["match", w / "huge.hdr", w / "R.png"], "header says 12000x12000", {}),
    ("rectify-left-huge-hdr", lambda w: ["rectify", w / "huge.hdr", w / "R.png", "--out", w / "rect"],
     "header says 12000x12000", {}),
    # numbers of 400 digits
    ("tune-targets-400-digits", lambda w: ["tune", *_pair(w), w / "targets_400_digits.json"], "pairs[0].left_xy", {}),
    ("match-params-400-digits", lambda w: ["match", *_pair(w), "--params-file", w / "params_400_digits.json"],
     "theta_c", {}),
    ("match-pixel-limit-400-digits", lambda w: ["match", *_pair(w)], "ISMB_LAB_MAX_PIXELS",
     {"ISMB_LAB_MAX_PIXELS": "9" * 400}),
    ("tune-generation-limit-400-digits", lambda w: _tune(w), "ISMB_LAB_MAX_GENERATIONS",
     {"ISMB_LAB_MAX_GENERATIONS": "9" * 400}),
    ("match-corner-limit-400-digits", lambda w: ["match", *_pair(w), "--n-max", "40"], "ISMB_LAB_MAX_CORNERS",
     {"ISMB_LAB_MAX_CORNERS": "9" * 400}),
    ("tune-generations-400-digits", lambda w: _tune(w, "--generations", "9" * 400), "an integer of 400 digits", {}),
    ("match-seed-10**30", lambda w: ["match", *_pair(w), "--seed", str(10**30)], "2**63 - 1", {}),
    ("depth-seed-2**64", lambda w: _depth(w, "--seed", str(2**64)), "2**63 - 1", {}),
    ("tune-seed-10**30", lambda w: _tune(w, "--seed", str(10**30), "--generations", "1"), "argument --seed", {}),
    ("evaluate-ga-seed-10**30", lambda w: ["evaluate", w / "manifest.json", "--ga-seed", str(10**30)],
     "argument --ga-seed", {}),
    # degenerate rigs
    ("rectify-rig-zero-k", lambda w: ["rectify", *_pair(w), "--rig", w / "rig_zero_k.json", "--out", w / "rect"],
     "'k_left'", {}),
    ("rectify-rig-nan-distortion", lambda w: ["rectify", *_pair(w), "--rig", w / "rig_nan_d.json",
                                              "--out", w / "rect"], "'d_left'", {}),
    ("rectify-rig-zero-baseline", lambda w: ["rectify", *_pair(w), "--rig", w / "rig_zero_baseline.json",
                                             "--out", w / "rect"], "'translation'", {}),
    ("rectify-rig-400-digits", lambda w: ["rectify", *_pair(w), "--rig", w / "rig_400_digits.json",
                                          "--out", w / "rect"], "'size'", {}),
    ("depth-rig-zero-baseline", lambda w: _depth(w, "--rig", w / "rig_zero_baseline.json"), "'translation'", {}),
    # render's output folder
    ("render-link-in-out", lambda w: ["render", "--out", w / "render_link"], "symbolic link", {}),
    ("render-fifo-in-out", lambda w: ["render", "--out", w / "render_fifo"], "FIFO", {}),
    ("render-readonly-in-out", lambda w: ["render", "--out", w / "render_readonly"], "read-only", {}),
    ("render-folder-link-in-out", lambda w: ["render", "--out", w / "render_folder_link"], "symbolic link", {}),
    # targets files of unbounded size
    ("tune-targets-too-many-pairs", lambda w: ["tune", *_pair(w), w / "targets_many_pairs.json"],
     "at most 10000 pairs", {}),
    ("tune-targets-too-many-bytes", lambda w: ["tune", *_pair(w), w / "targets_5mb.json"], "4194304 bytes", {}),
]


def test_the_sweep_is_large_enough():
    assert len(CASES) >= 40
    assert len({c[0] for c in CASES}) == len(CASES)
    assert {c[1](Path("/w"))[0] for c in CASES} == {"match", "tune", "evaluate", "depth", "render", "rectify",
                                                     "calibrate"}


@pytest.mark.parametrize("make_args, words, env", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_bad_input_is_one_line_exit_2_and_changes_no_file(ws, capsys, monkeypatch, make_args, words, env):
    args = [str(a) for a in make_args(ws)]
    if any("null_device" in a for a in args) and not (ws / "null_device").exists():
        pytest.skip("cannot make a character device here (mknod needs root)")
    for name, value in env.items():
        monkeypatch.setenv(name, value)
    before = snapshot(ws)
    code = main(args)
    err = capsys.readouterr().err
    assert code == 2, err
    assert len(err.strip().splitlines()) == 1 and err.startswith("ismb-lab: error:"), err
    assert words in err
    assert "Traceback" not in err and ".tmp" not in err
    assert snapshot(ws) == before
    assert stat.S_ISCHR(os.stat("/dev/null").st_mode)
