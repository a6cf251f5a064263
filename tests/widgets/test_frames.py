"""ipympl canvases of the widgets: one render at a time, every frame whole."""

import threading
import time

import matplotlib
import pytest
from matplotlib.figure import Figure

from ismb_lab.widgets._common import _serialise_frames


@pytest.fixture(autouse=True)
def keep_backend():
    """Importing ipympl switches matplotlib's backend; the other widget tests need Agg."""
    backend = matplotlib.get_backend()
    yield
    matplotlib.use(backend, force=True)


def ipympl_figure():
    from ipympl.backend_nbagg import Canvas, FigureManager

    fig = Figure(figsize=(2, 1))
    canvas = Canvas(fig)
    FigureManager(canvas, 0)
    line, = fig.add_subplot().plot([0, 1], [0, 1])
    sent = []
    canvas.send_binary = lambda data: sent.append(canvas._current_image_mode)
    return canvas, line, sent


def test_plain_ipympl_sends_diffs_but_serialised_canvases_send_whole_frames():
    canvas, line, sent = ipympl_figure()
    canvas.draw()
    line.set_ydata([1, 0])
    canvas.draw()
    assert sent == ["full", "diff"]
    canvas, line, sent = ipympl_figure()
    _serialise_frames(canvas)
    for y in ([1, 0], [0, 1], [1, 1]):
        line.set_ydata(y)
        canvas.draw()
    assert sent == ["full"] * 3


def test_two_threads_never_render_one_canvas_at_once():
    canvas, _, _ = ipympl_figure()
    inside, most = [0], [0]

    def slow_draw():
        inside[0] += 1
        most[0] = max(most[0], inside[0])
        time.sleep(0.05)
        inside[0] -= 1

    canvas.draw = slow_draw
    _serialise_frames(canvas)
    threads = [threading.Thread(target=canvas.draw) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert most[0] == 1
