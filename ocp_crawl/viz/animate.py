"""Animation of the crawling robot (like the paper's Fig. 1 snapshots): ``ocp-crawl animate``.

The steady cycle of a periodic gait is repeated ``cycles`` times, each repetition shifted by S
(a periodic gait is the same cycle translated).  A failed run is animated up to its failure.
Each foot is coloured by its contact state: sticking or slipping.  Frames are drawn on a
:class:`~matplotlib.figure.Figure` (no pyplot state) by blitting the moving artists over a
background drawn once, and written as a GIF with Pillow (a matplotlib dependency; no ffmpeg
needed), atomically.  :func:`crawl_animation` gives the same scene as a ``FuncAnimation`` for
notebooks.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import cast

import numpy as np
from matplotlib.animation import FuncAnimation
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D

from PIL import Image

from ocp_crawl.io import units
from ocp_crawl.io.files import atomic_write
from ocp_crawl.model.chain import Chain
from ocp_crawl.model.statics import Robot
from ocp_crawl.viz.gait import shape_points
from ocp_crawl.problem import Problem, run_problem
from ocp_crawl.sim.result import CrawlResult, Mode
from ocp_crawl.viz import FPS_BOUNDS

#: foot colours: sticking, slipping
STICK_COLOR = "#1a9850"
SLIP_COLOR = "#d73027"
MM = 1e3
#: bounds of the cycles shown and of the frames per cycle (``--cycles``, ``--frames-per-cycle``):
#: every frame is an image of about 0.2 MB held in memory until the GIF is written, so at most 1,000
#: frames (about 200 MB)
MAX_CYCLES, MAX_FRAMES_PER_CYCLE = 10, 100
FRAME_BOUNDS = {"--cycles": (1, MAX_CYCLES), "--frames-per-cycle": (2, MAX_FRAMES_PER_CYCLE)}


@dataclass(frozen=True)
class Frames:
    """The robot's state at each frame: phase [cycles from the start of the animation], feet and
    shape."""

    t: np.ndarray
    x1: np.ndarray
    x2: np.ndarray
    phi: np.ndarray
    """joint angles [rad], a row per joint"""
    theta: np.ndarray
    slip1: np.ndarray
    """foot 1 slipping at this frame"""
    slip2: np.ndarray
    mode: np.ndarray


def _mode(code: int) -> Mode | None:
    try:
        return Mode(int(code))
    except ValueError:  # a mode added later that this module does not know
        return None


def _slipping(mode: np.ndarray, foot: int) -> np.ndarray:
    return np.array([m is not None and m.foot in (foot, 3) for m in map(_mode, mode)], dtype=bool)


def frames_of(result: CrawlResult, cycles: int = 2, frames_per_cycle: int = 48) -> Frames:
    """Sample a result for animation: ``cycles`` repetitions of a steady cycle, or the run up to its
    failure.

    The result should be sampled densely (e.g. ``t_eval`` of a few hundred phases); frames take
    the nearest sample.  ``cycles`` in [1, MAX_CYCLES], ``frames_per_cycle`` in [2,
    MAX_FRAMES_PER_CYCLE]; a failed run is shown over its last ``cycles`` cycles up to the failure.
    """
    if not (1 <= cycles <= MAX_CYCLES and 2 <= frames_per_cycle <= MAX_FRAMES_PER_CYCLE):
        raise ValueError(f"cycles must be in [1, {MAX_CYCLES}] and frames_per_cycle in [2, "
                         f"{MAX_FRAMES_PER_CYCLE}], got {cycles}, {frames_per_cycle}")
    t = np.asarray(result.t, float) - result.t0
    if t.size == 0:
        raise ValueError("the result has no samples to animate")
    if result.success:
        n = cycles * frames_per_cycle + 1
        tf = np.linspace(0.0, float(cycles), n)
        rep = np.minimum(np.floor(tf).astype(int), cycles - 1)
        local = tf - rep
        shift = rep * result.S
    else:
        # the last cycles before the failure: at most cycles * frames_per_cycle
        start = max(t[0], t[-1] - cycles)
        n = max(2, int(round((t[-1] - start) * frames_per_cycle)) + 1)
        tf = np.linspace(start, t[-1], n)
        local, shift = tf, np.zeros(n)
    idx = np.clip(np.searchsorted(t, local), 0, t.size - 1)
    prev = np.clip(idx - 1, 0, t.size - 1)
    idx = np.where(np.abs(t[prev] - local) < np.abs(t[idx] - local), prev, idx)
    mode = np.asarray(result.mode, int)[idx]
    return Frames(tf, np.asarray(result.x1)[idx] + shift, np.asarray(result.x2)[idx] + shift,
                  np.asarray(result.phi)[:, idx], np.asarray(result.theta)[idx],
                  _slipping(mode, 1), _slipping(mode, 2), mode)


class CrawlScene:
    """The figure of the crawling robot and its moving artists; ``update(i)`` shows frame i."""

    def __init__(self, result: CrawlResult, robot: Robot | Chain, cycles: int = 2,
                 frames_per_cycle: int = 48, title: str | None = None):
        fr = self.frames = frames_of(result, cycles, frames_per_cycle)
        origin = fr.x1[0]
        # (frames, 2, points): foot 1, the joints, foot 2
        self.shapes = np.stack([MM * shape_points(robot, a - origin, b - origin, fr.phi[:, i], th)
                                for i, (a, b, th) in enumerate(zip(fr.x1, fr.x2, fr.theta))])
        xmin, xmax = self.shapes[:, 0].min(), self.shapes[:, 0].max()
        zmax = max(self.shapes[:, 1].max(), 1.0)
        pad = 0.08 * (xmax - xmin)
        # room above the robot for the legend and the phase label; the height follows the equal
        # aspect
        z_lo, z_hi = -0.15 * zmax, 1.9 * zmax
        aspect = (z_hi - z_lo) / (xmax - xmin + 2 * pad)
        fig = self.fig = Figure(figsize=(7.0, min(6.0, 0.8 + 6.2 * aspect)), dpi=100,
                                layout="constrained")
        FigureCanvasAgg(fig)
        ax = fig.subplots()
        ax.set_xlim(xmin - pad, xmax + pad)
        ax.set_ylim(z_lo, z_hi)
        ax.set_aspect("equal")
        ax.axhline(0.0, color="0.3", lw=1.5)
        ax.set_xlabel("x [mm] (from foot 1 at the start)")
        ax.set_ylabel("z [mm]")
        if title is None:
            title = f"{result.drive} drive, {result.gravity} gravity: " + \
                (f"S = {units.distance(result.S, 1)} per cycle, W$^+$ = "
                 f"{units.work(result.W_plus, 1)}, CoT$^+$ = {units.cot(result.CoT_plus)}"
                 if result.success else
                 f"{result.status_name.replace('_', ' ')} at t = {result.failure_t:.3f}")
        ax.set_title(title, fontsize="medium")
        ax.legend(handles=[Line2D([], [], ls="none", marker="o", mfc=STICK_COLOR, mec="k",
                                  label="foot sticks"),
                           Line2D([], [], ls="none", marker="o", mfc=SLIP_COLOR, mec="k",
                                  label="foot slips"),
                           Line2D([], [], color="0.75", lw=1, label="path of the joints")],
                  loc="upper right", fontsize="small")
        # the moving artists are "animated": a full draw leaves them out, so the static background
        # is drawn once and each frame only blits them (a full draw per frame is ~30x slower)
        self.traces = [ax.plot([], [], color="0.75", lw=1, animated=True)[0]
                       for _ in range(self.shapes.shape[2] - 2)]
        self.body, = ax.plot([], [], "-o", color="0.25", lw=3, ms=5, mfc="white", animated=True)
        self.feet = ax.scatter([0, 0], [0, 0], s=90, zorder=5, edgecolor="k", animated=True)
        self.label = ax.text(0.01, 0.97, "", transform=ax.transAxes, va="top", fontsize="small",
                             animated=True)
        self.ax = ax
        # lay out once: constrained layout would otherwise run again at every frame
        fig.draw_without_rendering()
        fig.set_layout_engine("none")

    @property
    def artists(self) -> tuple:
        return (*self.traces, self.body, self.feet, self.label)

    def __len__(self) -> int:
        return len(self.frames.t)

    def update(self, i: int) -> tuple:
        fr, pts = self.frames, self.shapes[i]
        self.body.set_data(pts[0], pts[1])
        self.feet.set_offsets(np.array([[pts[0, 0], 0.0], [pts[0, -1], 0.0]]))
        self.feet.set_facecolor([SLIP_COLOR if fr.slip1[i] else STICK_COLOR,
                                 SLIP_COLOR if fr.slip2[i] else STICK_COLOR])
        for j, trace in enumerate(self.traces, start=1):
            trace.set_data(self.shapes[:i + 1, 0, j], self.shapes[:i + 1, 1, j])
        m = _mode(fr.mode[i])
        name = m.label if m is not None else f"mode {int(fr.mode[i])}"
        self.label.set_text(f"t = {fr.t[i]:.2f} cycles, {name}")
        return self.artists

    def images(self) -> list[Image.Image]:
        """Every frame as a palette image (static background drawn once, moving artists blitted)."""
        canvas = cast(FigureCanvasAgg, self.fig.canvas)  # attached in __init__
        canvas.draw()
        background = canvas.copy_from_bbox(self.fig.bbox)
        out = []
        for i in range(len(self)):
            canvas.restore_region(background)
            for artist in self.update(i):
                self.ax.draw_artist(artist)
            rgba = np.asarray(canvas.buffer_rgba())
            out.append(Image.fromarray(rgba[..., :3].copy()).quantize(
                colors=64, method=Image.Quantize.FASTOCTREE))
        return out


def crawl_animation(result: CrawlResult, robot: Robot | Chain, cycles: int = 2,
                    frames_per_cycle: int = 48, title: str | None = None,
                    interval_ms: float = 50.0) -> FuncAnimation:
    """A FuncAnimation of the crawling robot (for notebooks; feet green when sticking, red when
    slipping)."""
    scene = CrawlScene(result, robot, cycles, frames_per_cycle, title)
    return FuncAnimation(scene.fig, scene.update, frames=len(scene), interval=interval_ms,
                         blit=True)


def save_gif(scene: CrawlScene, path: str | os.PathLike, fps: float = 20.0) -> Path:
    """Write the scene's frames as a looping GIF, atomically (``fps`` [1/s] in
    :data:`~ocp_crawl.viz.FPS_BOUNDS`)."""
    if not FPS_BOUNDS[0] <= fps <= FPS_BOUNDS[1]:
        raise ValueError(f"fps = {fps!r}: a GIF takes {FPS_BOUNDS[0]:g} to {FPS_BOUNDS[1]:g} "
                         "frames per second")
    frames = scene.images()
    duration = int(round(1000.0 / fps))
    return atomic_write(path,
                        lambda fh: frames[0].save(fh, format="GIF", save_all=True,
                                                  append_images=frames[1:],
                                                  duration=duration, loop=0))


def animate_problem(problem: Problem, path: str | os.PathLike, cycles: int = 2,
                    frames_per_cycle: int = 48, fps: int = 20) -> tuple[CrawlResult, Path | None]:
    """Simulate a problem and write its animation; returns the result (check ``success``) and the
    GIF path, None when a failed run has no samples to draw (a failure at the start, or a
    simulator that reports none on failure, as the chain's)."""
    result = run_problem(problem)
    if result.success:
        # dense samples of the steady cycle; the frames pick the nearest one
        result = run_problem(problem, t_eval=np.linspace(0.0, 1.0, 8 * frames_per_cycle + 1))
    elif len(result.t) == 0:
        return result, None
    scene = CrawlScene(result, problem.robot, cycles, frames_per_cycle)
    return result, save_gif(scene, path, fps)
