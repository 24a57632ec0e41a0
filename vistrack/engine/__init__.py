"""The batch engine: Dask tasks and the ``--out`` lock (:mod:`~vistrack.engine.grid`), task files
(:mod:`~vistrack.engine.tasks`), ``eval``'s tasks and summaries (:mod:`~vistrack.engine.evaluation`),
reports and plots."""
