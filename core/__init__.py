"""pinbore.core, the ground floor: what every stage needs and nothing that knows a stage.

- `errors`: InputError, the error a user can fix (one line, exit code 2);
- `scene`: strict TOML scene models (`Strict`), reading and validation into one-line errors;
- `output`: outputs that appear whole or not at all;
- `figures`: pictures written byte for byte the same from the same data;
- `html`: the pieces of the report page (figures inline, tables);
- `cpp`: the compiled core (C++, cpp/): the contact laws, the multibody engine, the
  elasto-plastic return map.

It imports no stage: `pinbore.laws`, `meshes`, `fem`, `calibration`, `reduced` build on it.
"""

if __name__ != "pinbore.core":   # one module, one name: never a second copy as `core`
    raise ImportError("core/ is the package pinbore.core: import pinbore.core")
