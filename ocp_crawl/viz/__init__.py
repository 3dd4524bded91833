"""Figures and animations: gait figure, OCP figure, crawl animation."""
