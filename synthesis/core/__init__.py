"""The solve core every kind stands on.

    problem.py     declare an NLP without naming a solver: variables, structural rows, rules, objective
    transcribe.py  a declaration -> decision vector, rows and bounds (back-off, elastic form, epigraphs)
    ipopt.py       the one place that calls ``nlpsol``: named option presets, one solve from a start
    executor.py    fixed-seed starts through a process pool or a dask cluster
    verdict.py     the fine-grid re-check of a start, the best start, the status and the exit-3 message
    solve.py       the multistart run of any kind, from its declared pieces to a Result
    kind.py        the kind contract: what a kind package exports
    coordinates.py reparametrisations (Grashof coordinates) that keep the kinematics defined at every iterate
    starts.py      moving drawn starts into the region where the kinematics is defined
    cluster.py     the dask.distributed path of the executor (imported only with --scheduler)
"""
