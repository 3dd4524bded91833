"""Figures and animations: the gait figure (:mod:`~ocp_crawl.viz.gait`), the OCP figure
(:mod:`~ocp_crawl.viz.ocp`) and the crawl animation (:mod:`~ocp_crawl.viz.animate`)."""
from ocp_crawl.io.lazy import lazy_exports

#: frames per second of a GIF [1/s]: from one frame per 100 s (a GIF frame's delay is a 16-bit count
#: of centiseconds, at most 655.35 s) to 100 per second (``animate --fps``; here, not in animate.py,
#: so that the command line checks it without importing matplotlib)
FPS_BOUNDS = (0.01, 100.0)

#: public name -> the module that defines it (imported on first use: start-up time, see io/lazy.py)
_EXPORTS = {
    "animate_problem": "ocp_crawl.viz.animate", "crawl_animation": "ocp_crawl.viz.animate",
    "save_gif": "ocp_crawl.viz.animate",
    "plot_gait": "ocp_crawl.viz.gait", "save_figure": "ocp_crawl.viz.gait",
    "plot_optimal_gait": "ocp_crawl.viz.ocp",
}

__all__ = ["animate_problem", "crawl_animation", "plot_gait", "plot_optimal_gait", "save_figure",
           "save_gif"]
__getattr__, __dir__ = lazy_exports(__name__, _EXPORTS)
