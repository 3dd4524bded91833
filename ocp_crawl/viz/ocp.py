"""Files and figures of an optimal-gait solve: torques.csv, optimal_gait.toml, arrays.npz, summary.json, figures."""
from __future__ import annotations

import io
import os
from pathlib import Path

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ocp_crawl.io.files import atomic_write, jsonable, write_json
from ocp_crawl.io.tables import table_text
from ocp_crawl.model.inputs import Harmonic, ReferenceTorque
from ocp_crawl.model.statics import Robot
from ocp_crawl.ocp import OCPResult
from ocp_crawl.ocp.solve import REPLAY_INTERPOLATION
from ocp_crawl.problem.overrides import toml_text
from ocp_crawl.problem.waveforms import samples_problem
from ocp_crawl.viz.gait import mode_color, mode_runs, plot_friction_limits, save_figure


def torques_csv(result: OCPResult) -> str:
    """CSV text of the optimal torques in the package's table convention (:mod:`ocp_crawl.io.tables`):
    ``phase [-]`` in [0, 1), ``tau1 [N m]``, ``tau2 [N m]``, one row per node, full precision (read back, the
    numbers are the very same, so that ``simulate`` of :data:`OPTIMAL_GAIT_TOML` reproduces the replay)."""
    return table_text([("phase", "-", result.phase), ("tau1", "N m", result.tau[0]), ("tau2", "N m", result.tau[1])],
                      comments=[f"optimal {result.objective} torques at the {result.phase.size} nodes of one cycle "
                                f"(status {result.status.label}); replay: ocp-crawl simulate {OPTIMAL_GAIT_TOML}"])


#: the problem file ``write_outputs`` writes next to torques.csv: the robot driven by the optimal torques
OPTIMAL_GAIT_TOML = "optimal_gait.toml"


def optimal_gait_toml(result: OCPResult, problem: dict) -> str:
    """A problem file replaying the optimum: ``problem``'s robot and gravity convention (sections as
    ``Problem.to_dict()``), the samples waveform reading torques.csv with the replay's interpolation."""
    sections = samples_problem(problem, "torques.csv", REPLAY_INTERPOLATION)
    return toml_text(sections, comments=[
        f"The optimal {result.objective} torque profile ({result.status.label}), written by ocp-crawl optimize.",
        f"Run:  ocp-crawl simulate {OPTIMAL_GAIT_TOML}  (S reproduces the optimize replay, S_replay).",
        "torques.csv (next to this file): phase [-], tau1 [N m], tau2 [N m] at the nodes, full precision."])


def plot_optimal_gait(result: OCPResult, robot: Robot) -> Figure:
    """Torques and angles over the cycle against the best harmonic gait, contact positions and modes,
    and the tangential force with the friction limits, all from the event-driven replay."""
    fig = Figure(figsize=(11, 9), constrained_layout=True)
    FigureCanvasAgg(fig)
    axs = fig.subplots(2, 2)
    rep = result.replay[0] if result.replay else None
    h = result.harmonic
    harm_sig = ReferenceTorque(Harmonic.from_degrees(h.gamma_deg, h.A_deg, h.psi_deg), robot.k) if h else None
    tt = np.linspace(0, 1, 401)
    ax = axs[0, 0]
    for i, c in enumerate(("tab:blue", "tab:purple")):
        ax.plot(np.r_[result.phase, 1.0], np.r_[result.tau[i], result.tau[i, 0]] * 1e3, color=c, marker=".",
                label=f"optimal tau{i + 1}")
        if harm_sig is not None:
            ax.plot(tt, harm_sig(tt)[i] * 1e3, color=c, ls="--", label=f"harmonic tau{i + 1}")
    ax.set_xlabel("phase t [cycles]")
    ax.set_ylabel("joint torque [mN m]")
    ax.set_title(f"torques ({result.objective})")
    ax.legend(fontsize=7)
    ax = axs[0, 1]
    if rep is not None:
        tr = rep.t - rep.t0
        for i, c in enumerate(("tab:blue", "tab:purple")):
            ax.plot(tr, np.degrees(rep.phi[i]), color=c, label=f"optimal phi{i + 1} (replay)")
        phi_ocp = result.phi[0]
        ax.plot(np.arange(phi_ocp.shape[1]) / (phi_ocp.shape[1] - 1), np.degrees(phi_ocp[0]), "k.", ms=3,
                label="OCP nodes")
        ax.plot(np.arange(phi_ocp.shape[1]) / (phi_ocp.shape[1] - 1), np.degrees(phi_ocp[1]), "k.", ms=3)
    if h is not None:
        ax.plot(tt, np.degrees(Harmonic.from_degrees(h.gamma_deg, h.A_deg, h.psi_deg)(tt)).T, ls="--", color="gray",
                lw=0.8, label="harmonic reference")
    ax.set_xlabel("phase t [cycles]")
    ax.set_ylabel("joint angle [deg]")
    ax.set_title("angles")
    ax.legend(fontsize=7)
    ax = axs[1, 0]
    if rep is not None:
        tr = rep.t - rep.t0
        for a, b, code in mode_runs(tr, rep.mode):
            ax.axvspan(a, b, color=mode_color(code), alpha=0.15, lw=0)
        ax.plot(tr, (rep.x1 - rep.x1[0]) * 1e3, color="tab:blue", label="x1 (replay)")
        ax.plot(tr, (rep.x2 - rep.x1[0]) * 1e3, color="tab:purple", label="x2 (replay)")
        ax.plot(np.arange(len(result.x1[0])) / (len(result.x1[0]) - 1), (result.x1[0] - result.x1[0][0]) * 1e3,
                "k.", ms=3, label="x1 (OCP nodes)")
    ax.set_xlabel("phase t [cycles]")
    ax.set_ylabel("contact position [mm]")
    ax.set_title("contact positions (shading: contact mode)")
    ax.legend(fontsize=7)
    ax = axs[1, 1]
    if rep is not None:
        tr = rep.t - rep.t0
        ax.plot(tr, rep.f_t * 1e3, "k", label="f_t")
        plot_friction_limits(ax, tr, robot, rep.f_n1, rep.f_n2, colors=("tab:blue", "tab:purple"), scale=1e3,
                             labels=("+- mu1 f_n1", "+- mu2 f_n2"))
    ax.set_xlabel("phase t [cycles]")
    ax.set_ylabel("tangential force [mN]")
    ax.set_title("forces and friction limits (replay)")
    ax.legend(fontsize=7)
    return fig


def write_outputs(result: OCPResult, robot: Robot, out_dir: str | os.PathLike, summary: dict) -> list[Path]:
    """Write torques.csv, optimal_gait.toml (a problem file replaying torques.csv, when ``summary`` holds the
    ``problem`` as ``Problem.to_dict()``), arrays.npz, summary.json and the figure (PNG, PDF) atomically into
    out_dir; returns the paths written."""
    out = Path(out_dir)
    written = [atomic_write(out / "torques.csv", lambda fh: fh.write(torques_csv(result).encode()))]
    if result.phase.size and "problem" in summary:
        text = optimal_gait_toml(result, summary["problem"]).encode()
        written.append(atomic_write(out / OPTIMAL_GAIT_TOML, lambda fh: fh.write(text)))
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
