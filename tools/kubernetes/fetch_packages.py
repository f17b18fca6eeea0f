#!/usr/bin/env python3
"""Installs the npm packages that package-lock.json pins into node_modules/, without npm.

  python3 tools/kubernetes/fetch_packages.py

What `npm ci` does for this lock file (no package in it has install scripts), in the standard
library: each package's tarball from the npm registry ($npm_config_registry, else
registry.npmjs.org), checked against the lock file's SHA-512 before anything is unpacked, then
unpacked into the path the lock file names. Debian's npm package would bring about 400 packages
with it; Node.js itself (Debian's nodejs) is all the schema check needs besides these files.
Writes node_modules/ under a temporary name and renames it into place, so an interrupted run
leaves the old folder or none. Exit 1, naming the package, on a download or checksum failure.
"""
import base64
import hashlib
import io
import json
import os
import shutil
import sys
import tarfile
import tempfile
import urllib.request


def main():
    here = os.path.dirname(os.path.realpath(__file__))
    with open(os.path.join(here, "package-lock.json")) as f:
        lock = json.load(f)
    registry = os.environ.get("npm_config_registry", "https://registry.npmjs.org/").rstrip("/")
    staging = tempfile.mkdtemp(prefix=".node_modules.", dir=here)
    try:
        for path, entry in lock["packages"].items():
            if not path:
                continue  # the root project itself
            name = path.rsplit("node_modules/", 1)[1]
            version, integrity = entry["version"], entry["integrity"]
            algorithm, _, digest = integrity.partition("-")
            if algorithm != "sha512":
                sys.exit(f"error: {name}@{version}: integrity {algorithm} is not sha512")
            url = f"{registry}/{name}/-/{name.split('/')[-1]}-{version}.tgz"
            try:
                with urllib.request.urlopen(url, timeout=60) as response:
                    data = response.read()
            except OSError as e:
                sys.exit(f"error: {name}@{version}: cannot download {url}: {e}")
            if base64.b64encode(hashlib.sha512(data).digest()).decode() != digest:
                sys.exit(f"error: {name}@{version}: {url} does not match the lock file's SHA-512")
            target = os.path.join(staging, os.path.relpath(path, "node_modules"))
            with tarfile.open(fileobj=io.BytesIO(data), mode="r:gz") as tar:
                for member in tar.getmembers():
                    # npm tarballs hold one top folder (usually "package/"): strip it.
                    parts = member.name.split("/", 1)
                    if len(parts) < 2 or not (member.isfile() or member.isdir()):
                        continue
                    relative = os.path.normpath(parts[1])
                    if relative.startswith("..") or os.path.isabs(relative):
                        sys.exit(f"error: {name}@{version}: {member.name} leaves the package")
                    destination = os.path.join(target, relative)
                    if member.isdir():
                        os.makedirs(destination, exist_ok=True)
                        continue
                    os.makedirs(os.path.dirname(destination), exist_ok=True)
                    with tar.extractfile(member) as src, open(destination, "wb") as out:
                        shutil.copyfileobj(src, out)
        # The marker tools/setup.sh compares with the lock file (npm writes the same file).
        shutil.copyfile(os.path.join(here, "package-lock.json"),
                        os.path.join(staging, ".package-lock.json"))
        final = os.path.join(here, "node_modules")
        if os.path.isdir(final):
            shutil.rmtree(final)
        os.rename(staging, final)
        staging = None
        print(f"installed {len(lock['packages']) - 1} packages into {final}")
    finally:
        if staging:
            shutil.rmtree(staging, ignore_errors=True)


if __name__ == "__main__":
    main()
