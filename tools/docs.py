#!/usr/bin/env python3
"""Writes the generated parts of the documentation from the program's own descriptions, or checks
them (--check): docs/cli.md's block from `cadsynth --help` and every subcommand's --help,
docs/recipes.md's block from `cadsynth generate --help-recipe`, docs/parts.md's family table
from `cadsynth variants --families` (variants/families.cpp's rows), and recipes/recipe.schema.json
from `cadsynth generate --recipe-schema`. The CLI11 texts and the recipe tree are the one
description; these files are copies a reader finds without running the program, and the ctest
`docs_generated` fails when they drift.

  tools/docs.py --cadsynth build/tools/cadsynth           # rewrite the generated parts
  tools/docs.py --cadsynth build/tools/cadsynth --check   # exit 1, naming the file, if stale
"""
import argparse
import pathlib
import re
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent
BEGIN, END = "<!-- begin generated -->", "<!-- end generated -->"


def run(cadsynth, *args):
    out = subprocess.run([cadsynth, *args], check=True, capture_output=True, text=True).stdout
    return out.rstrip() + "\n"


def subcommands(help_text):
    """The commands the top-level help's usage lines name ("  cadsynth NAME ..."), in order."""
    names = []
    for m in re.finditer(r"^  cadsynth ([a-z][a-z-]*)\b", help_text, re.M):
        if m.group(1) not in names:
            names.append(m.group(1))
    return names


def cli_block(cadsynth):
    top = run(cadsynth, "--help")
    parts = ["```text\n$ cadsynth --help\n" + top + "```\n"]
    for name in subcommands(top):
        parts.append(f"#### cadsynth {name}\n\n```text\n$ cadsynth {name} --help\n" +
                     run(cadsynth, name, "--help") + "```\n")
    return "\n".join(parts)


def recipe_block(cadsynth):
    return "```yaml\n" + run(cadsynth, "generate", "--help-recipe") + "```\n"


def families_block(cadsynth):
    return run(cadsynth, "variants", "--families")


def replace_block(text, block, path):
    if BEGIN not in text or END not in text:
        sys.exit(f"{path}: no {BEGIN} ... {END} block")
    head, rest = text.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    return head + BEGIN + "\n" + block + END + tail


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cadsynth", required=True, help="the cadsynth executable")
    parser.add_argument("--check", action="store_true", help="fail if a file is stale")
    args = parser.parse_args()
    wanted = {}
    for rel, block in (("docs/cli.md", cli_block(args.cadsynth)),
                       ("docs/recipes.md", recipe_block(args.cadsynth)),
                       ("docs/parts.md", families_block(args.cadsynth))):
        path = ROOT / rel
        wanted[path] = replace_block(path.read_text(), block, rel)
    wanted[ROOT / "recipes/recipe.schema.json"] = run(args.cadsynth, "generate", "--recipe-schema")
    stale = [p for p, text in wanted.items() if not p.exists() or p.read_text() != text]
    if args.check:
        for p in stale:
            print(f"{p.relative_to(ROOT)}: out of date with the program; run tools/docs.py "
                  f"--cadsynth {args.cadsynth}", file=sys.stderr)
        return 1 if stale else 0
    for p in stale:
        p.write_text(wanted[p])
        print(f"wrote {p.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
