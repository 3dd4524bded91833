"""Files and figures of an optimal-gait solve: torques.csv, optimal_gait.toml, arrays.npz,
summary.json, figures."""
from __future__ import annotations

import io
import math
import os
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ocp_crawl.io import units
from ocp_crawl.io.files import atomic_write, jsonable, write_json
from ocp_crawl.io.tables import table_text
from ocp_crawl.model.chain_inputs import JointCallable
from ocp_crawl.model.inputs import CallableSignal
from ocp_crawl.ocp import OCPResult, OCPSettings
from ocp_crawl.ocp.judge import REPLAY_INTERPOLATION, scenario_labels
from ocp_crawl.problem.overrides import toml_text
from ocp_crawl.problem.waveforms import samples_problem
from ocp_crawl.ocp.plant import Plant
from ocp_crawl.viz.gait import (mode_legend, mode_runs, plot_friction_limits, save_figure,
                                shade_modes)


def torques_csv(result: OCPResult) -> str:
    """CSV text of the optimal torques in the package's table convention
    (:mod:`ocp_crawl.io.tables`): ``phase [-]`` in [0, 1), ``tau1 [N m]`` .. ``taum [N m]`` (the m
    joints), one row per node, and ``period [s]``, the OCP's period T on every row (without a finite
    T, no such column); full precision (read back, the numbers are the very same, so that
    ``simulate`` of :data:`OPTIMAL_GAIT_TOML` reproduces the replay and its speed)."""
    columns = [("phase", "-", result.phase),
               *((f"tau{i + 1}", "N m", row) for i, row in enumerate(result.tau))]
    if math.isfinite(result.T_ocp):
        columns.append(("period", "s", np.full(result.phase.size, result.T_ocp)))
    return table_text(columns, comments=[
        f"optimal {result.objective} torques at the {result.phase.size} nodes of one cycle of "
        f"period T = {units.seconds(result.T_ocp)} (status {result.status.label}); replay: "
        f"ocp-crawl simulate {OPTIMAL_GAIT_TOML}"])


#: the problem file ``write_outputs`` writes next to torques.csv: the robot driven by the optimal
#: torques
OPTIMAL_GAIT_TOML = "optimal_gait.toml"


def _gait_sections(result: OCPResult, problem: dict) -> dict:
    """``problem``'s robot and gravity convention (sections as ``Problem.to_dict()``) driven by
    torques.csv with the replay's interpolation, over the OCP's period (``[gait] period``, when
    finite)."""
    sections = samples_problem(problem, "torques.csv", REPLAY_INTERPOLATION)
    if math.isfinite(result.T_ocp):
        sections["gait"]["period"] = float(result.T_ocp)
    return sections


def optimal_gait_toml(result: OCPResult, problem: dict) -> str:
    """A problem file replaying the optimum: ``problem``'s robot and gravity convention (sections as
    ``Problem.to_dict()``), the samples waveform reading torques.csv with the replay's
    interpolation, the OCP's period as ``[gait] period``."""
    return toml_text(_gait_sections(result, problem), comments=[
        f"The optimal {result.objective} torque profile ({result.status.label}), written by "
        "ocp-crawl optimize.",
        f"Run:  ocp-crawl simulate {OPTIMAL_GAIT_TOML}  (S and the speed reproduce the optimize "
        "replay's, S_replay and v_replay).",
        f"torques.csv (next to this file): phase [-], {_tau_columns(result)} at the nodes, full "
        "precision."])


def _tau_columns(result: OCPResult) -> str:
    m = result.tau.shape[0]
    return ", ".join(f"tau{i + 1} [N m]" for i in range(m)) if m <= 3 else \
        f"tau1 [N m] .. tau{m} [N m]"


def scenario_files(settings: OCPSettings) -> list[str]:
    """The problem files replaying each friction scenario of a friction set, named by its ratio
    mu1/mu2 (``optimal_gait_mu1_mu2_0.9.toml``, ...; with friction levels
    ``..._0.9_level_0.5.toml``, or ``optimal_gait_level_0.5.toml`` at the robot's own ratio:
    :func:`~ocp_crawl.ocp.judge.scenario_labels`); [] without a set."""
    if not settings.friction_set:
        return []
    return [f"optimal_gait_level_{label.removeprefix('own_level_')}.toml"
            if label.startswith("own_")
            else f"optimal_gait_mu1_mu2_{label}.toml" for label in scenario_labels(settings)]


def scenario_toml(result: OCPResult, problem: dict, scenario, label: str, name: str) -> str:
    """The problem file ``name`` replaying the optimum in one friction scenario ``label``
    (:func:`~ocp_crawl.ocp.judge.scenario_labels`): as
    :func:`optimal_gait_toml`, the robot's friction coefficients those of ``scenario`` (mu1, mu2,
    full precision)."""
    sections = _gait_sections(result, problem)
    robot: dict[str, Any] = {}
    # mu1 and mu2 where the problem gives its friction
    for key, value in sections["robot"].items():
        if key in ("mu", "mu1"):
            robot.update(mu1=scenario.mu1, mu2=scenario.mu2)
        elif key != "mu2":
            robot[key] = value
    sections["robot"] = robot
    return toml_text(sections, comments=[
        f"The optimal {result.objective} torque profile ({result.status.label}) in the friction "
        f"scenario mu1 = {scenario.mu1:.6g}, mu2 = {scenario.mu2:.6g} ({label}), written by "
        "ocp-crawl optimize.",
        f"Run:  ocp-crawl simulate {name}  (S and the speed reproduce the optimize replay's in "
        "this scenario).",
        f"torques.csv (next to this file): phase [-], {_tau_columns(result)} at the nodes, full "
        "precision."])


#: colours of joint/foot 1 and 2
JOINT_COLORS = ("tab:blue", "tab:purple")
#: colours of the joints of a chain of more than two joints
CHAIN_COLORS = ("tab:blue", "tab:orange", "tab:green", "tab:purple", "tab:brown", "tab:pink",
                "tab:olive", "tab:cyan")


def joint_colors(m: int) -> tuple:
    """The colours of m joints (the three-link robot's two: :data:`JOINT_COLORS`)."""
    if m == 2:
        return JOINT_COLORS
    return tuple(CHAIN_COLORS[i % len(CHAIN_COLORS)] for i in range(m))
#: opacity of the contact-mode shading
MODE_ALPHA = 0.45
#: the sign of f_t, in the label of every force axis
FT_SIGN = "on foot 1, along +x"


def _baseline(result: OCPResult):
    """The best simple gait: the best member of every waveform family searched (the harmonic
    without a search), the one the gain is over; None without one."""
    best = result.baselines.best if result.baselines else None
    return best if best is not None else result.harmonic


def pin_shift(signal) -> float:
    """The phase [cycles] at which the first joint's value of ``signal`` is largest (where the
    OCP pins its profile's phase 0)."""
    fine = np.arange(4096) / 4096
    return float(fine[int(np.argmax(np.asarray(signal(fine))[0]))])


def pinned(signal, t: np.ndarray) -> np.ndarray:
    """``signal`` at the phases ``t`` [cycles] shifted as the OCP pins its profile: phase 0 where
    the first joint's value is largest (a baseline drawn in the optimum's phase)."""
    return np.asarray(signal((np.asarray(t) + pin_shift(signal)) % 1.0))


def baseline_replays(result: OCPResult, robot) -> list:
    """The event-driven replays of the best simple gait (:func:`_baseline`), its torque pinned as
    the optimum's (:func:`pinned`), in every friction scenario of the optimum and in its gravity
    convention: the actual motion to compare the optimum's with; [] without a baseline or without
    a replay of the optimum."""
    best = _baseline(result)
    if best is None or not result.replay:
        return []
    torque = best.signal_for(robot, result.settings)
    shift = pin_shift(torque)
    shifted = CallableSignal if result.tau.shape[0] == 2 else JointCallable
    signal = shifted(lambda t: torque((np.asarray(t) + shift) % 1.0),
                     lambda t: torque.derivative((np.asarray(t) + shift) % 1.0))
    gravity = result.replay[0].gravity
    return [Plant(r, gravity).simulate(signal) for r in result.settings.scenarios(robot)]


#: the label of the time axis in cycles
PHASE_LABEL = "phase t/T [cycles]"


def _clock(result: OCPResult, best) -> tuple[float, float, str]:
    """The time axis: (seconds per cycle of the optimum, of the best simple gait, axis label); in
    seconds when the period of the optimum and that of a baseline drawn (the best simple gait, the
    best harmonic) differ, else in cycles (1, 1)."""
    T = result.T_ocp
    periods = [c.T for c in (best, result.harmonic) if c is not None]
    if math.isfinite(T) and all(math.isfinite(t) for t in periods) \
            and any(not math.isclose(T, t, rel_tol=1e-6) for t in periods):
        return T, best.T, "time [s] (one cycle of each gait)"
    return 1.0, 1.0, PHASE_LABEL


def _motion(S: float, T: float, W: float | None = None, cot: float | None = None) -> str:
    """S per cycle and the mean speed v = S/T, of one sign (S < 0: towards foot 1), and W+ and
    CoT+ when given."""
    text = f"S = {units.distance(S, 2)}, v = S/T = {units.speed(S / T if T > 0 else None, 1)}"
    if W is None:
        return text
    return text + f", W$^+$ = {units.work(W, 1)}, CoT$^+$ = {units.cot(cot)}"


def _title(result: OCPResult, best) -> str:
    """Headline: objective, status, periods, S, v, W+ and CoT+ of the replay and of the best
    simple gait, the gains over the waveform families."""
    head = f"Optimal {result.objective} gait ({result.settings.nodes} nodes): {result.status.label}"
    rep = result.replay[0] if result.replay else None
    if rep is None or not rep.success:
        return head + (f"\nOCP S = {units.distance(result.S_ocp[0], 2)} per cycle (not replayed)"
                       if result.S_ocp else "")
    name = f"best {best.shape} gait" if best is not None else ""
    head += f"; period T = {units.seconds(result.T_ocp)}"
    head += f" ({name}: {units.seconds(best.T)})" if best is not None else ""
    sign = "S per cycle, S < 0: towards foot 1"
    if len(result.replay) > 1:
        if result.objective == "min_cot":
            what, value = "CoT$^+$", units.cot(result.value_replay)
        elif result.objective not in ("max_speed", "robust_speed"):  # a user objective
            what, value = result.objective, units.significant(result.value_replay, 6)
        else:   # the objective's speed, signed as S
            what = "v = S/T"
            value = units.speed(result.settings.direction * result.value_replay, 1)
        head += (f"\n{result.settings.robust} {what} over the {len(result.replay)} friction "
                 f"scenarios (columns): {value}; {sign}")
    else:
        head += f"\nreplay: {_motion(rep.S, result.T_ocp, rep.W_plus, rep.CoT_plus)} ({sign})"
        if best is not None:
            head += f"\n{name}: {_motion(best.S[0], best.T, best.W_plus[0], best.CoT_plus[0])}"
    user = result.settings.user_objective
    if user is not None:  # its value, which the speeds and works above do not show
        unit = "" if user.unit == "-" else f" {user.unit}"
        theirs = (f", {name} {units.significant(best.value, 4)}{unit}" if best is not None
                  else "")
        head += (f"\n{result.objective} by replay: "
                 f"{units.significant(result.value_replay, 4)}{unit}{theirs}")
    significance = "" if result.gain_significant else " (not significant)"
    return head + "\n" + _gains_text(result, significance)


def _gains_text(result: OCPResult, significance: str) -> str:
    """The gains by replay over the best of the waveform families' members and over each."""
    parts = ", ".join(f"{shape} {units.ratio(g)}" for shape, g in result.gains.items())
    best = _baseline(result)
    name = best.shape if best is not None else "-"
    return (f"gain by replay over the best simple gait ({name}) {units.ratio(result.gain)}"
            f"{significance}\nover each waveform family's best: {parts}")


def _column_title(result: OCPResult, best, j: int, label: str) -> str:
    """The header of scenario ``j``'s column (mu1/mu2 = ``label``): the optimum's and the
    baseline's S and v."""
    rep = result.replay[j]
    text = f"friction mu1/mu2 = {label}\noptimum: "
    text += _motion(rep.S, result.T_ocp) if rep.success else rep.status_name
    if best is not None:
        text += f"\nbest {best.shape}: {_motion(best.S[j], best.T)}"
    return text + "\n\n"


def plot_optimal_gait(result: OCPResult, robot, baselines: list | None = None) -> Figure:
    """Four panels over the cycle, one column per friction scenario: (a) the optimal torques [mN m]
    against the best simple gaits', (b) the actual joint angles [deg] and (c) contact positions [mm]
    of the replay and the OCP's nodes against the best simple gait's own replay (``baselines``, one
    per scenario; default: :func:`baseline_replays`), (d) the tangential force [N] with the friction
    limits; every panel shaded by the contact modes of the optimum's replay.  ``robot``: the
    three-link Robot or a Chain (a curve per joint).  Time in seconds when the optimum's and the
    baseline's periods differ, else the phase.  The title gives S, v, W+ and CoT+ of the
    event-driven replays and the gains.  Returns the figure (Agg canvas)."""
    best = _baseline(result)
    runs = baseline_replays(result, robot) if baselines is None else baselines
    clock = _clock(result, best)
    n = max(len(result.replay), 1)
    fig = Figure(figsize=(4.0 + max(6.5, 4.6 * n), 13.5), layout="constrained")
    FigureCanvasAgg(fig)
    axs = fig.subplots(4, n, squeeze=False, sharex=True)
    fig.suptitle(_title(result, best))
    scenarios = result.settings.scenarios(robot)
    labels = scenario_labels(result.settings)
    name = f"best {best.shape}" if best is not None else ""
    modes: set[int] = set()
    for j in range(n):
        ax = axs[:, j]
        rep = result.replay[j] if j < len(result.replay) else None
        base = (runs[j] if j < len(runs) else None, name)
        if rep is not None:
            for a in ax:
                modes |= shade_modes(a, mode_runs((rep.t - rep.t0) * clock[0], rep.mode),
                                     alpha=MODE_ALPHA)
        _torques(ax[0], result, robot, best, clock)
        _angles(ax[1], result, j, rep, base, clock)
        _positions(ax[2], result, j, rep, base, clock)
        _forces(ax[3], result, rep, scenarios[min(j, len(scenarios) - 1)], clock)
        if n > 1 and rep is not None:
            head = _column_title(result, best, j, labels[j])
            ax[0].set_title(head + ax[0].get_title(loc="left"), loc="left", fontsize="medium")
        ax[-1].set_xlabel(clock[2])
    for a in axs[:, -1]:   # one legend per row, right of the last column: off the curves
        if a.get_legend_handles_labels()[0]:
            a.legend(loc="center left", bbox_to_anchor=(1.02, 0.5), fontsize="small")
    if modes:
        patches, names = mode_legend(modes, alpha=MODE_ALPHA)
        fig.legend(patches, names, loc="outside lower center", ncol=min(len(names), 3),
                   fontsize="small", title_fontsize="small",
                   title="background of every panel: contact mode of the optimum's replay")
    fig.draw_without_rendering()
    fig.set_layout_engine("none")
    return fig


def _label(ax, title: str, ylabel: str) -> None:
    ax.set_ylabel(ylabel)
    ax.set_title(title, loc="left", fontsize="medium")
    ax.grid(True, lw=0.3, alpha=0.6)
    ax.tick_params(labelbottom=True)


def _torques(ax, result: OCPResult, robot, best, clock) -> None:
    """Panel (a): the optimal node torques, the best harmonic gait's and the best simple gait's
    (when that is of another family), both pinned as the optimum (:func:`pinned`), each over its
    own period."""
    tt = np.linspace(0, 1, 401)
    h = result.harmonic
    others = [(h, "--", "best harmonic")] if h is not None else []
    if best is not None and best is not h:
        others.append((best, "-.", f"best {best.shape}"))
    nodes = np.r_[result.phase, 1.0] * clock[0]
    for i, c in enumerate(joint_colors(result.tau.shape[0])):
        ax.plot(nodes, np.r_[result.tau[i], result.tau[i, 0]] * 1e3, color=c, marker=".", ms=4,
                label=f"optimal $\\tau_{i + 1}$ (nodes)")
        for choice, ls, name in others:   # each over its own period, when in seconds
            tau = pinned(choice.signal_for(robot, result.settings), tt)[i] * 1e3
            period = 1.0 if clock[2] == PHASE_LABEL else choice.T
            ax.plot(tt * period, tau, color=c, ls=ls, lw=1.0, label=f"{name} $\\tau_{i + 1}$")
    _label(ax, f"(a) joint torques ({result.objective})", "joint torque [mN m]")


def _angles(ax, result: OCPResult, j: int, rep, baseline: tuple, clock) -> None:
    """Panel (b): the actual joint angles of the optimum (replay and OCP nodes) and of the best
    simple gait (``baseline``: its own replay and its name)."""
    colors = joint_colors(result.tau.shape[0])
    if rep is not None:
        tr = (rep.t - rep.t0) * clock[0]
        # joint 1 wide and below, the others thin on top: optimal gaits often move joints alike
        for i, c in enumerate(colors):
            ax.plot(tr, np.degrees(rep.phi[i]), color=c, lw=3.0 if i == 0 else 1.4,
                    alpha=0.6 if i == 0 else 1.0, zorder=3 if i == 0 else 4,
                    label=f"optimal $\\varphi_{i + 1}$ (replay)")
    if j < len(result.phi):
        phi = result.phi[j]
        nodes = np.arange(phi.shape[1]) / (phi.shape[1] - 1) * clock[0]
        for i in range(phi.shape[0]):
            ax.plot(nodes, np.degrees(phi[i]), ls="none", marker="osD^v<>p"[i % 8], ms=3.0,
                    mfc="none", mec="0.35", mew=0.6, zorder=5,
                    label=f"OCP nodes $\\varphi_{i + 1}$")
    base, name = baseline
    if base is not None and base.t.size:
        tb = (base.t - base.t0) * clock[1]
        for i, c in enumerate(colors):
            ax.plot(tb, np.degrees(base.phi[i]), color=c, ls="--", lw=1.0, zorder=4,
                    label=f"{name} $\\varphi_{i + 1}$ (its replay)")
    _label(ax, "(b) actual joint angles", "joint angle [deg]")


def _positions(ax, result: OCPResult, j: int, rep, baseline: tuple, clock) -> None:
    """Panel (c): the contact positions of the optimum (replay, OCP nodes) and of the best simple
    gait (``baseline``), each from its foot 1 at the start of the cycle."""
    if rep is not None:
        tr = (rep.t - rep.t0) * clock[0]
        for x, c, i in ((rep.x1, JOINT_COLORS[0], 1), (rep.x2, JOINT_COLORS[1], 2)):
            ax.plot(tr, (x - rep.x1[0]) * 1e3, color=c, label=f"optimal $x_{i}$ (replay)")
    if j < len(result.x1):
        x1 = result.x1[j]
        nodes = np.arange(len(x1)) / (len(x1) - 1) * clock[0]
        ax.plot(nodes, (x1 - x1[0]) * 1e3, ls="none", marker="o", ms=3.0, mfc="none", mec="0.35",
                mew=0.6, zorder=5, label="OCP nodes $x_1$")
    base, name = baseline
    if base is not None and base.t.size:
        tb = (base.t - base.t0) * clock[1]
        for x, c, i in ((base.x1, JOINT_COLORS[0], 1), (base.x2, JOINT_COLORS[1], 2)):
            ax.plot(tb, (x - base.x1[0]) * 1e3, color=c, ls="--", lw=1.0,
                    label=f"{name} $x_{i}$ (its replay)")
    _label(ax, "(c) contact positions (from foot 1 at the start)", "contact position [mm]")


def _forces(ax, result: OCPResult, rep, robot, clock) -> None:
    """Panel (d): the replay's tangential force [N] and the friction limits of the scenario's
    ``robot``."""
    if rep is not None:
        tr = (rep.t - rep.t0) * clock[0]
        ax.plot(tr, rep.f_t, "k", label="optimal $f_t$ (replay)")
        plot_friction_limits(ax, tr, robot, rep.f_n1, rep.f_n2, colors=JOINT_COLORS)
    else:  # a failed solve is not replayed: say so instead of an empty panel
        ax.text(0.5, 0.5, f"no replay: the OCP's result is {result.status.label}", ha="center",
                va="center", transform=ax.transAxes, fontsize="small")
    _label(ax, "(d) tangential force and friction limits", f"tangential force [N]\n({FT_SIGN})")


def _write_text(path: Path, text: str) -> Path:
    data = text.encode()
    return atomic_write(path, lambda fh: fh.write(data))


def write_outputs(result: OCPResult, robot, out_dir: str | os.PathLike,
                  summary: dict) -> list[Path]:
    """Write torques.csv, optimal_gait.toml (a problem file replaying torques.csv, when ``summary``
    holds the ``problem`` as ``Problem.to_dict()``; over a friction set: also one per friction
    scenario, :func:`scenario_files`), arrays.npz, summary.json and the figure (PNG, PDF) atomically
    into out_dir; returns the paths written."""
    out = Path(out_dir)
    written = [_write_text(out / "torques.csv", torques_csv(result))]
    if result.phase.size and "problem" in summary:
        problem = summary["problem"]
        written.append(_write_text(out / OPTIMAL_GAIT_TOML, optimal_gait_toml(result, problem)))
        labels = scenario_labels(result.settings)
        for name, label, scenario in zip(scenario_files(result.settings), labels,
                                         result.settings.scenarios(robot)):
            written.append(_write_text(out / name,
                                       scenario_toml(result, problem, scenario, label, name)))
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
