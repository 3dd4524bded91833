"""Figures and animations: the gait figure (:mod:`~ocp_crawl.viz.gait`), the OCP figure
(:mod:`~ocp_crawl.viz.ocp`) and the crawl animation (:mod:`~ocp_crawl.viz.animate`)."""
from ocp_crawl.viz.animate import animate_problem, crawl_animation, save_gif
from ocp_crawl.viz.gait import plot_gait, save_figure
from ocp_crawl.viz.ocp import plot_optimal_gait

__all__ = ["animate_problem", "crawl_animation", "plot_gait", "plot_optimal_gait", "save_figure", "save_gif"]
