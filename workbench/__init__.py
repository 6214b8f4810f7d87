"""Particle-methods workbench: shared layer (scenes, materials, analytic references, results, CLI)."""

__version__ = "0.1.0"
