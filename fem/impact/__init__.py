"""The dynamic impact of the pin in its bore (`pinbore impact SCENE --out DIR`): the impact
scene and its Liu-law estimate of the contact that sizes the mesh and the time step
(scene.py), the implicit time integration of the two elastic or elasto-plastic bodies with
the contact terms of fem.contact (solver.py), the run that steps an impact scene through to
its outputs (run.py), and those outputs' files, history.csv and impact.json, defined once for
the run that writes them and the calibration, report, benchmarks and tests that read them
(file.py)."""
