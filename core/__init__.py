"""pinbore.core, the ground floor: what every stage needs and nothing that knows a stage.

- `errors`: InputError, the error a user can fix (one line, exit code 2);
- `scene`: strict TOML scene models (`Strict`), reading and validation into one-line errors,
  `Record` for the files between stages;
- `output`: outputs that appear whole or not at all;
- `figures`: pictures written byte for byte the same from the same data;
- `html`: the pieces of the report page (figures inline, tables);
- `parallel`: the one runner of many points (local processes or a Dask cluster), each
  result cached by content;
- `uq`: sampling plans and statistics: intervals, exceedance, Sobol indices, polynomial
  chaos, tolerance bands;
- `codedeps`: the code a stage runs, its import closure read from the source (make's
  dependencies, the caches' keys);
- `cpp`: the compiled core (C++, cpp/): the contact laws, the multibody engine, the
  elasto-plastic return map.

It imports no stage: `pinbore.laws`, `meshes`, `fem`, `calibration`, `reduced` build on it.
"""

if __name__ != "pinbore.core":   # one module, one name: never a second copy as `core`
    raise ImportError("core/ is the package pinbore.core: import pinbore.core")
