"""highway-env as a world and its IDM/MOBIL driver as a stack (issue #39).

Nothing of highway-env is ported: its environments build the roads, its vehicles drive, its
road steps them and checks collisions. rocas supplies a frozen, typed scene (:mod:`.scene`),
seeds highway-env's randomness from its own seed, overrides the ego driver's class constants
per run (:mod:`.params`), reads the driver's decision at its own seams (perception, planning,
control, :mod:`.driver`), records those channels with their topology (:mod:`.record`), and
runs the co-mutation over scenes and driver parameters (:mod:`.comutation`).

highway-env is an optional extra: ``pip install 'rocas[highway]'``. Importing this package
does not import it; :func:`rocas.stacks.highway.hwenv.require` does, or says how to install it.
"""
