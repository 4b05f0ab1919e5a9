"""Guide tubes of seed 001 §2.4: wall angles that make every pot seedling land at the same time.

drag.py   closed forms of straight-line motion with quadratic drag (floats and CasADi symbols)
drop.py   the five-phase drop through one tube (eq 13-23), closed form
slope.py  the analytic derivative dt_z/d(delta) of the closed form (checks CasADi's AD)
ode.py    the same drop integrated with scipy solve_ivp, phase switches as events
printed.py eq 17/19/21 exactly as printed (superposition reading), for the readings study
calibrate.py friction coefficient from a measured landing time
scene.py, check.py, nlp.py, solve.py, plots.py: the guide_tube kind of the CLI
"""
