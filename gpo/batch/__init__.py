"""Many runs at once: sweeps over recordings x configs on Dask (``sweep``), resumable, gathered into one table.

``spec`` (the sweep's YAML), ``runs`` (one run, its key, its execution on a worker), ``cluster`` (local, or one
reached by its scheduler's address), ``table`` (the results, read and summarised) and ``sweep`` (the runs sent to the
cluster, their results kept as they finish)."""
