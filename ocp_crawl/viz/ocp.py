"""Files and figures of an optimal-gait solve: torques.csv, optimal_gait.toml, arrays.npz, summary.json, figures."""
from __future__ import annotations

import io
import math
import os
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ocp_crawl.io import units
from ocp_crawl.io.files import atomic_write, jsonable, write_json
from ocp_crawl.io.tables import table_text
from ocp_crawl.model.inputs import ReferenceTorque
from ocp_crawl.model.statics import Robot
from ocp_crawl.ocp import OCPResult, OCPSettings
from ocp_crawl.ocp.judge import REPLAY_INTERPOLATION, ratio_labels, value_text
from ocp_crawl.problem.overrides import toml_text
from ocp_crawl.problem.waveforms import samples_problem
from ocp_crawl.viz.gait import mode_legend, mode_runs, plot_friction_limits, save_figure, shade_modes


def torques_csv(result: OCPResult) -> str:
    """CSV text of the optimal torques in the package's table convention (:mod:`ocp_crawl.io.tables`):
    ``phase [-]`` in [0, 1), ``tau1 [N m]``, ``tau2 [N m]``, one row per node, and ``period [s]``, the OCP's
    period T on every row (without a finite T, no such column); full precision (read back, the numbers are the
    very same, so that ``simulate`` of :data:`OPTIMAL_GAIT_TOML` reproduces the replay and its speed)."""
    columns = [("phase", "-", result.phase), ("tau1", "N m", result.tau[0]), ("tau2", "N m", result.tau[1])]
    if math.isfinite(result.T_ocp):
        columns.append(("period", "s", np.full(result.phase.size, result.T_ocp)))
    return table_text(columns, comments=[
        f"optimal {result.objective} torques at the {result.phase.size} nodes of one cycle of period T = "
        f"{units.seconds(result.T_ocp)} (status {result.status.label}); replay: ocp-crawl simulate "
        f"{OPTIMAL_GAIT_TOML}"])


#: the problem file ``write_outputs`` writes next to torques.csv: the robot driven by the optimal torques
OPTIMAL_GAIT_TOML = "optimal_gait.toml"


def _gait_sections(result: OCPResult, problem: dict) -> dict:
    """``problem``'s robot and gravity convention (sections as ``Problem.to_dict()``) driven by torques.csv with the
    replay's interpolation, over the OCP's period (``[gait] period``, when finite)."""
    sections = samples_problem(problem, "torques.csv", REPLAY_INTERPOLATION)
    if math.isfinite(result.T_ocp):
        sections["gait"]["period"] = float(result.T_ocp)
    return sections


def optimal_gait_toml(result: OCPResult, problem: dict) -> str:
    """A problem file replaying the optimum: ``problem``'s robot and gravity convention (sections as
    ``Problem.to_dict()``), the samples waveform reading torques.csv with the replay's interpolation, the OCP's
    period as ``[gait] period``."""
    return toml_text(_gait_sections(result, problem), comments=[
        f"The optimal {result.objective} torque profile ({result.status.label}), written by ocp-crawl optimize.",
        f"Run:  ocp-crawl simulate {OPTIMAL_GAIT_TOML}  (S and the speed reproduce the optimize replay's, S_replay "
        "and v_replay).",
        "torques.csv (next to this file): phase [-], tau1 [N m], tau2 [N m] at the nodes, full precision."])


def scenario_files(settings: OCPSettings) -> list[str]:
    """The problem files replaying each friction scenario of a friction set, named by its ratio mu1/mu2
    (``optimal_gait_mu1_mu2_0.9.toml``, ...; :func:`~ocp_crawl.ocp.judge.ratio_labels`); [] without a
    set."""
    if not settings.friction_set:
        return []
    return [f"optimal_gait_mu1_mu2_{label}.toml" for label in ratio_labels(settings.friction_ratios)]


def scenario_toml(result: OCPResult, problem: dict, scenario: Robot, label: str, name: str) -> str:
    """The problem file ``name`` replaying the optimum in one friction scenario, mu1/mu2 = ``label``: as
    :func:`optimal_gait_toml`, the robot's friction coefficients those of ``scenario`` (mu1, mu2, full precision)."""
    sections = _gait_sections(result, problem)
    robot = {}
    for key, value in sections["robot"].items():   # mu1 and mu2 where the problem gives its friction
        if key in ("mu", "mu1"):
            robot.update(mu1=scenario.mu1, mu2=scenario.mu2)
        elif key != "mu2":
            robot[key] = value
    sections["robot"] = robot
    return toml_text(sections, comments=[
        f"The optimal {result.objective} torque profile ({result.status.label}) in the friction scenario mu1/mu2 = "
        f"{label}, written by ocp-crawl optimize.",
        f"Run:  ocp-crawl simulate {name}  (S and the speed reproduce the optimize replay's in this scenario).",
        "torques.csv (next to this file): phase [-], tau1 [N m], tau2 [N m] at the nodes, full precision."])


#: colours of joint/foot 1 and 2
JOINT_COLORS = ("tab:blue", "tab:purple")


def _title(result: OCPResult) -> str:
    """Headline: objective, status, S, W+ and CoT+ of the replay, gains over the waveform families."""
    rep = result.replay[0] if result.replay else None
    head = f"Optimal {result.objective} gait ({result.settings.nodes} nodes): {result.status.label}"
    if rep is None or not rep.success:
        return head + (f"\nOCP S = {units.distance(result.S_ocp[0], 2)} per cycle (not replayed)" if result.S_ocp
                       else "")
    significance = "" if result.gain_significant else " (not significant)"
    if len(result.replay) > 1:  # a friction set: the objective is over the scenarios, the panels: the first
        what = "CoT$^+$" if result.objective == "min_cot" else "speed"
        head += (f"\n{result.settings.robust} {what} over the {len(result.replay)} friction scenarios "
                 f"{value_text(result.objective, result.value_replay)}; panels and the line below: the "
                 f"first, mu1/mu2 = {result.settings.friction_ratios[0]:.2f}")
    return (head + f"\nreplay: S = {units.distance(rep.S, 2)} per cycle, T = {units.seconds(result.T_ocp)}, "
            f"v = {units.speed(result.v_replay[0] if result.v_replay else None, 1)}, W$^+$ = "
            f"{units.work(rep.W_plus, 1)}, CoT$^+$ = {units.cot(rep.CoT_plus)}\n{_gains_text(result, significance)}")


def _gains_text(result: OCPResult, significance: str) -> str:
    """The gains by replay over the best of the waveform families' members and, on a second line, over each."""
    parts = ", ".join(f"{shape} {units.ratio(g)}" for shape, g in result.gains.items())
    best = result.baselines.best if result.baselines else result.harmonic
    name = best.shape if best is not None else "-"
    return (f"gain by replay over the best simple gait ({name}) {units.ratio(result.gain)}{significance}\n"
            f"over each waveform family's best: {parts}")


def plot_optimal_gait(result: OCPResult, robot: Robot) -> Figure:
    """Four panels over the cycle: (a) the optimal torques [mN m] against the best harmonic gait's, (b) the
    joint angles [deg] of the replay with the OCP's nodes and the harmonic reference, (c) the contact
    positions [mm] over the contact modes of the replay, (d) the tangential force [mN] with the friction
    limits.  The title gives S, W+ and CoT+ of the event-driven replay and the gain over the best harmonic
    gait.  Returns the figure (Agg canvas)."""
    fig = Figure(figsize=(11, 9.5), layout="constrained")
    FigureCanvasAgg(fig)
    axs = fig.subplots(2, 2)
    fig.suptitle(_title(result))
    rep = result.replay[0] if result.replay else None
    h = result.harmonic
    gait = h.gait() if h else None
    best = result.baselines.best if result.baselines else None
    other = best if best is not None and best.shape != "harmonic" else None
    _torques(axs[0, 0], result, ReferenceTorque(gait, robot.k) if gait else None,
             other.torque_signal(robot.k) if other else None, other.shape if other else "")
    _angles(axs[0, 1], result, rep, gait)
    modes = _positions(axs[1, 0], result, rep)
    ax = axs[1, 1]
    if rep is not None:
        tr = rep.t - rep.t0
        ax.plot(tr, rep.f_t * 1e3, "k", label="$f_t$")
        plot_friction_limits(ax, tr, robot, rep.f_n1, rep.f_n2, colors=JOINT_COLORS, scale=1e3)
    else:  # a failed solve is not replayed: say so instead of an empty panel
        ax.text(0.5, 0.5, f"no replay: the OCP's result is {result.status.label}", ha="center", va="center",
                transform=ax.transAxes, fontsize="small")
    _label(ax, "(d) tangential force and friction limits (replay)", "tangential force [mN]")
    if modes:
        patches, names = mode_legend(modes, alpha=MODE_ALPHA)
        fig.legend(patches, names, loc="outside lower center", ncol=min(len(names), 3), fontsize="small",
                   title="shading of (c): contact mode of the replay", title_fontsize="small")
    fig.draw_without_rendering()
    fig.set_layout_engine("none")
    return fig


#: opacity of the contact-mode shading of panel (c)
MODE_ALPHA = 0.45


def _label(ax, title: str, ylabel: str) -> None:
    ax.set_xlabel("phase t [cycles]")
    ax.set_ylabel(ylabel)
    ax.set_title(title, loc="left", fontsize="medium")
    ax.grid(True, lw=0.3, alpha=0.6)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize="small")


def pinned(signal, t: np.ndarray) -> np.ndarray:
    """``signal`` at the phases ``t`` [cycles] shifted as the OCP pins its profile: phase 0 where the first
    joint's value is largest (a baseline drawn in the optimum's phase)."""
    fine = np.arange(4096) / 4096
    shift = fine[int(np.argmax(np.asarray(signal(fine))[0]))]
    return np.asarray(signal((t + shift) % 1.0))


def _torques(ax, result: OCPResult, harmonic: ReferenceTorque | None, other=None, name: str = "") -> None:
    """Panel (a): the optimal node torques, the best harmonic gait's and (``other``) the best gait of
    the family ``name`` when that is the best baseline, both pinned as the optimum (:func:`pinned`)."""
    tt = np.linspace(0, 1, 401)
    for i, c in enumerate(JOINT_COLORS):
        ax.plot(np.r_[result.phase, 1.0], np.r_[result.tau[i], result.tau[i, 0]] * 1e3, color=c, marker=".",
                ms=4, label=f"optimal $\\tau_{i + 1}$ (nodes)")
        if harmonic is not None:
            ax.plot(tt, pinned(harmonic, tt)[i] * 1e3, color=c, ls="--", lw=1.0,
                    label=f"best harmonic $\\tau_{i + 1}$ (pinned)")
        if other is not None:
            ax.plot(tt, pinned(other, tt)[i] * 1e3, color=c, ls="-.", lw=1.0,
                    label=f"best {name} $\\tau_{i + 1}$ (pinned)")
    _label(ax, f"(a) joint torques ({result.objective})", "joint torque [mN m]")


def _angles(ax, result: OCPResult, rep, gait) -> None:
    if rep is not None:
        tr = rep.t - rep.t0
        # joint 1 wide and below, joint 2 dashed on top: optimal gaits often move both joints alike
        ax.plot(tr, np.degrees(rep.phi[0]), color=JOINT_COLORS[0], lw=3.0, alpha=0.8, zorder=3,
                label="optimal $\\varphi_1$ (replay)")
        ax.plot(tr, np.degrees(rep.phi[1]), color=JOINT_COLORS[1], lw=1.4, ls="--", zorder=4,
                label="optimal $\\varphi_2$ (replay)")
    phi = result.phi[0]
    nodes = np.arange(phi.shape[1]) / (phi.shape[1] - 1)
    for i, marker in enumerate(("o", "s")):
        ax.plot(nodes, np.degrees(phi[i]), ls="none", marker=marker, ms=3.0, mfc="none", mec="0.35", mew=0.6,
                zorder=2, label=f"OCP nodes $\\varphi_{i + 1}$")
    if gait is not None:
        tt = np.linspace(0, 1, 401)
        ref = np.degrees(pinned(gait, tt))
        for i, c in enumerate(JOINT_COLORS):
            ax.plot(tt, ref[i], ls=":", color=c, lw=1.0, label=f"harmonic reference $\\varphi_{{{i + 1},\\mathrm{{ref}}}}$ (pinned)")
    _label(ax, "(b) joint angles", "joint angle [deg]")


def _positions(ax, result: OCPResult, rep) -> set[int]:
    """Panel (c); returns the contact modes shaded."""
    drawn: set[int] = set()
    if rep is not None:
        tr = rep.t - rep.t0
        drawn = shade_modes(ax, mode_runs(tr, rep.mode), alpha=MODE_ALPHA)
        ax.plot(tr, (rep.x1 - rep.x1[0]) * 1e3, color=JOINT_COLORS[0], label="$x_1$ (replay)")
        ax.plot(tr, (rep.x2 - rep.x1[0]) * 1e3, color=JOINT_COLORS[1], label="$x_2$ (replay)")
    x1 = result.x1[0]
    ax.plot(np.arange(len(x1)) / (len(x1) - 1), (x1 - x1[0]) * 1e3, ls="none", marker="o", ms=3.0, mfc="none",
            mec="0.35", mew=0.6, label="$x_1$ (OCP nodes)")
    _label(ax, "(c) contact positions", "contact position [mm]")
    return drawn


def _write_text(path: Path, text: str) -> Path:
    data = text.encode()
    return atomic_write(path, lambda fh: fh.write(data))


def write_outputs(result: OCPResult, robot: Robot, out_dir: str | os.PathLike, summary: dict) -> list[Path]:
    """Write torques.csv, optimal_gait.toml (a problem file replaying torques.csv, when ``summary`` holds
    the ``problem`` as ``Problem.to_dict()``; over a friction set: also one per friction scenario,
    :func:`scenario_files`), arrays.npz, summary.json and the figure (PNG, PDF) atomically into out_dir;
    returns the paths written."""
    out = Path(out_dir)
    written = [_write_text(out / "torques.csv", torques_csv(result))]
    if result.phase.size and "problem" in summary:
        problem = summary["problem"]
        written.append(_write_text(out / OPTIMAL_GAIT_TOML, optimal_gait_toml(result, problem)))
        labels = ratio_labels(result.settings.friction_ratios)
        for name, label, scenario in zip(scenario_files(result.settings), labels,
                                         result.settings.scenarios(robot)):
            written.append(_write_text(out / name, scenario_toml(result, problem, scenario, label, name)))
    arrays = {"phase": result.phase, "tau": result.tau}
    for j, (phi, x1, ft) in enumerate(zip(result.phi, result.x1, result.f_t)):
        arrays[f"phi_{j}"] = phi
        arrays[f"x1_{j}"] = x1
        arrays[f"f_t_{j}"] = ft
        arrays[f"mode_{j}"] = np.asarray(result.modes[j])
    for j, rep in enumerate(result.replay):
        for k, v in rep.arrays().items():
            arrays[f"replay_{j}_{k}"] = v

    def npz(fh):
        buf = io.BytesIO()
        np.savez(buf, **arrays)
        fh.write(buf.getvalue())

    written.append(atomic_write(out / "arrays.npz", npz))
    written.append(write_json(out / "summary.json", jsonable(summary)))
    if result.phase.size:
        fig = plot_optimal_gait(result, robot)
        for ext in ("png", "pdf"):
            written.append(save_figure(fig, out / f"optimal_gait.{ext}"))
    return written
