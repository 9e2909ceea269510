"""A body's FE model reduced to a flexible body (`pinbore modes SCENE --out DIR`): the scene
(scene.py: the body of meshes.body, its material, the reduction), the reduction itself
(reduction.py: M and K with DOLFINx, Craig-Bampton with rigid interfaces and SLEPc, the free
modes in the mean-axis frame, the inertia invariants and the geometric stiffening from M), the
run (run.py), the reduced body's files body.npz and modes.json, defined once for the run that
writes them and the mechanisms, report and tests that read them (file.py), and the report's
section (report.py)."""
