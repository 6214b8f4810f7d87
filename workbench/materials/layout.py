"""Layouts of the material library's flat arrays (the parameter row ``prm`` and the history of a
point): the constants every module of :mod:`workbench.materials` shares (the table of slots is in
the package docstring)."""
from __future__ import annotations

LAW_CODES = {"svk": 0, "neo_hooke": 1, "mooney_rivlin": 2, "j2": 3, "mortar": 4, "brittle": 5}
HARDENING_CODES = {"swift": 0, "linear": 1}
FAILURE_CODES = {"literal": 0, "compression": 1}
N_PARAMS = 12
N_HISTORY_J2 = 13
HIST_EPS_P = 9
HIST_DAMAGE = 10
HIST_W_P = 11
HIST_W_REL = 12
