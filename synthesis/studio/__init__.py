"""``agrisynth studio``: a local interactive design page.

Move a design value, see the mechanism, its path and every rule margin of the kind's own ``check``
redrawn; solve from there with the kind's NLP (``agrisynth solve``, in a worker process); save the
values as a spec.  Served on 127.0.0.1 only, behind a random token; needs the ``studio`` extra
(starlette, uvicorn).  :mod:`.session` evaluates, :mod:`.grids` says on which grid, :mod:`.drawing`
reads what to draw from the check's result, :mod:`.solver` runs solves, :mod:`.server` serves the page.
"""
