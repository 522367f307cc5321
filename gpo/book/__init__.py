"""The book: what the chapters show. One module per chapter of ``notebooks/`` (``chNN_*``: its figures and panels),
and what several chapters share (``figures``, ``panels``, ``shown``). It imports the layers below it (the core, the
method, the simulated world and the experiments, where the papers' tables are computed); none of them imports it, and
it runs commands as a user does, ``python -m gpo`` in a subprocess, never by importing the command line.
"""
