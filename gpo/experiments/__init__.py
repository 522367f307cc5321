"""The papers' experiments, as the chapters, the command line and the benchmarks run them: the first paper's Tables
1, 3 and 4, the second paper's Table 2, and the floor runs they share, kept on disk (``runs``).

Above the method and the simulated world, which it imports; below the book and the command line, which it never
imports."""
