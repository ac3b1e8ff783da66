"""A second stack under test, modelled on LAV (Chen et al., 2022), written independently of
:mod:`rocas.stacks.ads`: joint perception-and-prediction (pnp), a learned brake model on the telephoto
camera (brake), a waypoint planner with ``plan_collide`` (planner), a PID controller with LAV's
post-processing (controller), and gnss. Select it with ``get_stack("lav")``."""
