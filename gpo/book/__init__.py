"""The book: what the chapters show. One module per chapter of ``notebooks/`` (``chNN_*``: its figures, panels and
experiments, the papers' tables among them), and what several chapters share (``figures``, ``panels``, ``runs``).
It imports from both layers below it, the method (``gpo``) and the simulated world (``gpo.sim``); neither imports it.
"""
