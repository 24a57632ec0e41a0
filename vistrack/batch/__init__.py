"""Running many tasks: the Dask cluster, the task files, the ``--out`` lock and resume."""
