#!/usr/bin/env python3
"""The recipe's JSON Schema (`cadsynth generate --recipe-schema`) checked by an independent
validator, Debian's python3-jsonschema: the schema is valid Draft 2020-12, every shipped recipe
passes it, and recipes with a misspelled key, a key of another light type, a wrong kind of value
or a missing required key fail it, as cadsynth itself refuses them. Exits 77 (skipped) without
jsonschema or PyYAML.

  recipe_schema_test.py CADSYNTH_EXECUTABLE
"""
import copy
import json
import pathlib
import subprocess
import sys
import tempfile

try:
    import jsonschema
    import yaml
except ImportError as e:
    print(f"skipped: {e} (tools/setup.sh --tests installs python3-jsonschema)")
    sys.exit(77)

ROOT = pathlib.Path(__file__).resolve().parents[2]
failures = []


def check(ok, what):
    print(("ok   " if ok else "FAIL ") + what)
    if not ok:
        failures.append(what)


def main():
    cadsynth = sys.argv[1]
    schema = json.loads(subprocess.run([cadsynth, "generate", "--recipe-schema"], check=True,
                                       capture_output=True, text=True).stdout)
    jsonschema.Draft202012Validator.check_schema(schema)
    validator = jsonschema.Draft202012Validator(schema)

    recipes = sorted((ROOT / "recipes").glob("*.yaml"))
    check(len(recipes) >= 10, f"{len(recipes)} shipped recipes found")
    for path in recipes:
        errors = [f"{'.'.join(map(str, e.absolute_path))}: {e.message}"
                  for e in validator.iter_errors(yaml.safe_load(path.read_text()))]
        check(not errors, f"{path.name} passes the schema" + (f": {errors[:3]}" if errors else ""))

    base = yaml.safe_load((ROOT / "recipes" / "pbr_demo.yaml").read_text())
    check(validator.is_valid(base), "pbr_demo.yaml is the base of the broken recipes")

    def broken(what, edit, refused_by_cadsynth=True):
        recipe = copy.deepcopy(base)
        edit(recipe)
        check(not validator.is_valid(recipe), f"the schema rejects {what}")
        if refused_by_cadsynth:
            # cadsynth itself refuses the same recipe, naming the file (both read one description).
            with tempfile.TemporaryDirectory() as tmp:
                path = pathlib.Path(tmp) / "broken.yaml"
                path.write_text(yaml.safe_dump(recipe))
                run = subprocess.run([cadsynth, "generate", str(path), "-o", f"{tmp}/out",
                                      "--no-cache", "--quiet"], capture_output=True, text=True,
                                     cwd=ROOT / "recipes")
                check(run.returncode == 1 and "broken.yaml:" in run.stderr,
                      f"cadsynth refuses {what}: {run.stderr.strip()[:160]}")

    broken("a misspelled top-level section", lambda r: r.update(sweeep=r.pop("sweep")))
    broken("a misspelled sweep key", lambda r: r["sweep"].update(yaww=0))
    broken("a misspelled material key",
           lambda r: r["materials"]["assign"][0].update(roughnes=0.2))
    broken("spot_size on a rect light",
           lambda r: r["lighting"]["lights"][0].update(type="rect", spot_size=30))
    broken("a light without a type", lambda r: r["lighting"]["lights"][0].pop("type"))
    broken("a word where a whole number goes", lambda r: r["render"].update(samples="many"))
    broken("an unknown render mode", lambda r: r["render"].update(mode="raytraced"))
    broken("an unknown depth model", lambda r: r.setdefault("camera", {}).update(depth="lidar"))

    # The committed copy for editors is the program's own (tools/docs.py writes it).
    shipped = json.loads((ROOT / "recipes" / "recipe.schema.json").read_text())
    check(shipped == schema, "recipes/recipe.schema.json is --recipe-schema's output")
    print(f"{len(failures)} failed" if failures else "all passed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
