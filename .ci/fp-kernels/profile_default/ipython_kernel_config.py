# IPython's settings for the kernels of the checks on the other floating-point paths (Makefile: the fp-avx2 and
# fp-sse4 phases run with IPYTHONDIR=.ci/fp-kernels). Those checks compare the text a chapter prints; its figures are
# drawn and shown in the pytest phase, under nbval and in the browser test. Here a figure is shown as its text alone
# ("<Figure size 700x280 with 1 Axes>", the output nbval compares), without making its PNG, which nbval does not
# compare: chapters 06 and 07 run in about a tenth less time.
c = get_config()  # noqa: F821 (IPython's loader defines it)
c.InlineBackend.figure_formats = set()
c.HistoryManager.enabled = False
