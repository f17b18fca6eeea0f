#!/usr/bin/env python3
"""The Kubernetes manifests (tools/kubernetes/) as a cluster would take them.

  kubernetes_test.py schema SOURCE_DIR
      Every manifest against the Kubernetes API schema (tools/kubernetes/validate.js, through the
      kubernetes-models package that `tools/setup.sh --tests` installs with npm). Exit 77
      (skipped), saying why, where Node or the package is missing.

  kubernetes_test.py run SOURCE_DIR CADSYNTH_EXE
      Runs the Indexed Job's command as Kubernetes would: one process per completion index with
      JOB_COMPLETION_INDEX set, the volumes as local folders, `parallelism` at a time; one pod
      killed part-way and started again (restartPolicy: OnFailure), one index run again after it
      succeeded; then the merge Job's command. The merged dataset must equal a single process's
      byte for byte. Then the same recipe as an AWS Batch array job (AWS_BATCH_JOB_ARRAY_INDEX and
      _SIZE), and the errors of `--shard auto` without a task index or with a count that disagrees.
"""
import hashlib
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time

try:
    import yaml
except ImportError:
    print("SKIPPED: Python has no yaml module: install Debian's python3-yaml (tools/setup.sh --tests does)")
    sys.exit(77)

SCHEDULER_VARIABLES = ("SLURM_ARRAY_TASK_ID", "SLURM_ARRAY_TASK_MIN", "SLURM_ARRAY_TASK_MAX",
                       "SLURM_ARRAY_TASK_COUNT", "JOB_COMPLETION_INDEX",
                       "AWS_BATCH_JOB_ARRAY_INDEX", "AWS_BATCH_JOB_ARRAY_SIZE",
                       "BATCH_TASK_INDEX", "BATCH_TASK_COUNT")

# The default job's three scenes at 160x120, five views each: 15 units, two for most of the Job's
# eight pods; the AWS Batch array of 20 has five children that own none (they must finish cleanly).
RECIPE = """\
camera: {preset: kinect_v1, width: 160, height: 120, fx: 131.25, fy: 131.25, cx: 79.5, cy: 59.5}
sweep: {yaw: [0, 72, 144, 216, 288], pitch: [40], radius: 0.8 m}
output: {formats: [bop, coco]}
"""


def fail(message):
    print("FAIL: " + message)
    sys.exit(1)


def manifests(source):
    folder = os.path.join(source, "tools", "kubernetes")
    objects = []
    for name in sorted(os.listdir(folder)):
        if not name.endswith(".yaml"):
            continue
        with open(os.path.join(folder, name)) as f:
            for i, doc in enumerate(yaml.safe_load_all(f)):
                if doc is not None:
                    objects.append({"source": f"{name}#{i + 1}", "file": name, "object": doc})
    return objects


def check_schema(source):
    node = shutil.which("node")
    if node is None:
        print("SKIPPED: node not found: install Debian's nodejs and npm (tools/setup.sh --tests does)")
        return 77
    package = os.path.join(source, "tools", "kubernetes", "node_modules", "kubernetes-models")
    if not os.path.isdir(package):
        print("SKIPPED: " + package + " is missing: run `python3 tools/kubernetes/fetch_packages.py` "
              "(tools/setup.sh --tests does)")
        return 77
    objects = manifests(source)
    kinds = sorted({(o["object"].get("kind"), o["object"]["metadata"]["name"]) for o in objects})
    expected = [("Job", "cadsynth-merge"), ("Job", "cadsynth-shards"),
                ("PersistentVolumeClaim", "cadsynth-data")]
    if kinds != expected:
        fail(f"tools/kubernetes/ holds {kinds}, expected {expected}")
    validator = os.path.join(source, "tools", "kubernetes", "validate.js")
    with tempfile.TemporaryDirectory() as work:
        listing = os.path.join(work, "objects.json")

        def validate(items):
            with open(listing, "w") as f:
                json.dump([{"source": o["source"], "object": o["object"]} for o in items], f)
            return subprocess.run([node, validator, listing], capture_output=True, text=True)

        result = validate(objects)
        print(result.stdout + result.stderr, end="")
        if result.returncode != 0:
            fail("a manifest does not match the Kubernetes API schema")
        # The validator itself must catch what the API server would refuse.
        shards = next(o for o in objects if o["object"]["metadata"]["name"] == "cadsynth-shards")
        broken = []
        for path, value in ((("spec", "completionMode"), "Indexd"),
                            (("spec", "completions"), "8"),
                            (("spec", "template", "spec", "containers", 0, "resources",
                              "requests", "memory"), "1 GB")):
            copy = json.loads(json.dumps(shards))
            target = copy["object"]
            for key in path[:-1]:
                target = target[key]
            target[path[-1]] = value
            copy["source"] = "/".join(str(p) for p in path) + "=" + repr(value)
            broken.append(copy)
        for item in broken:
            result = validate([item])
            if result.returncode == 0:
                fail("the validator accepted " + item["source"] + ": " + result.stdout)
            print("refused as it should be: " + result.stdout.strip())
    print("PASS: the manifests match the Kubernetes API schema")
    return 0


def tree_digest(root, skip=()):
    """Relative path -> SHA-256 of every file under root (but the folders named in skip, and
    run.json: how the run went, its time and shards)."""
    digest = {}
    for folder, folders, files in os.walk(root):
        folders[:] = [f for f in folders if f not in skip]
        for name in files:
            if name == "run.json" and os.path.samefile(folder, root):
                continue
            path = os.path.join(folder, name)
            with open(path, "rb") as f:
                digest[os.path.relpath(path, root)] = hashlib.sha256(f.read()).hexdigest()
    return digest


def expect_same_tree(expected, actual, what):
    a, b = tree_digest(expected), tree_digest(actual)
    if a != b:
        missing = sorted(set(a) - set(b))[:5]
        extra = sorted(set(b) - set(a))[:5]
        differ = sorted(k for k in set(a) & set(b) if a[k] != b[k])[:5]
        fail(f"{what} differs from a single process: missing {missing}, extra {extra}, "
             f"different {differ}")
    print(f"{what}: {len(a)} files, byte for byte a single process's")


def clean_environment(**variables):
    env = {k: v for k, v in os.environ.items() if k not in SCHEDULER_VARIABLES}
    env.update({k: str(v) for k, v in variables.items()})
    return env


class Pod:
    """The manifest's container command, its mounts mapped to local folders."""

    def __init__(self, job, exe, mounts):
        spec = job["spec"]["template"]["spec"]
        container = spec["containers"][0]
        self.command = list(container["command"])
        if self.command[0] != "cadsynth":
            fail(f"the container command starts with {self.command[0]!r}, not cadsynth")
        self.command[0] = exe
        volume_claims = {v["name"]: v for v in spec.get("volumes", [])}
        for mount in container.get("volumeMounts", []):
            if mount["name"] not in volume_claims:
                fail(f"volumeMount {mount['name']} names no volume")
            local = mounts[mount["name"]]
            self.command = [arg.replace(mount["mountPath"], local, 1)
                            if arg.startswith(mount["mountPath"]) else arg
                            for arg in self.command]

    def start(self, log, **variables):
        return subprocess.Popen(self.command, env=clean_environment(**variables), stdout=log,
                                stderr=subprocess.STDOUT)


def run_jobs(source, exe):
    jobs = {o["object"]["metadata"]["name"]: o["object"] for o in manifests(source)}
    shards_job, merge_job = jobs["cadsynth-shards"], jobs["cadsynth-merge"]
    spec = shards_job["spec"]
    if spec.get("completionMode") != "Indexed":
        fail("cadsynth-shards is not an Indexed Job")
    completions, parallelism = spec["completions"], spec.get("parallelism", 1)
    command = shards_job["spec"]["template"]["spec"]["containers"][0]["command"]
    if "--shard" not in command or command[command.index("--shard") + 1] != "auto":
        fail(f"the shards' command does not take its shard from the Job: {command}")
    if "--shards" not in command or command[command.index("--shards") + 1] != str(completions):
        fail(f"the shards' command must give --shards {completions} (the Job's completions): {command}")
    restart = spec["template"]["spec"]["restartPolicy"]
    if restart != "OnFailure":
        fail(f"restartPolicy {restart}: a failed pod must start again in place (OnFailure)")

    work = tempfile.mkdtemp(prefix="cadsynth_kubernetes.")
    try:
        os.makedirs(os.path.join(work, "recipe"))
        os.makedirs(os.path.join(work, "data"))
        with open(os.path.join(work, "recipe", "recipe.yaml"), "w") as f:
            f.write(RECIPE)
        mounts = {"recipe": os.path.join(work, "recipe"), "data": os.path.join(work, "data")}
        cache = os.path.join(work, "cache")
        single = os.path.join(work, "single")
        subprocess.run([exe, "generate", os.path.join(work, "recipe", "recipe.yaml"), "-o", single,
                        "--quiet", "--cache", cache], check=True, env=clean_environment())

        pod = Pod(shards_job, exe, mounts)
        pod.command += ["--cache", cache]
        out = pod.command[pod.command.index("-o") + 1]
        log = open(os.path.join(work, "pods.log"), "w")

        # Index 1's first pod is evicted part-way: killed once its first frame is on the volume.
        first = pod.start(log, JOB_COMPLETION_INDEX=1)
        deadline = time.time() + 600
        while first.poll() is None and time.time() < deadline:
            if os.path.isdir(out) and any(f.endswith(".png") for _, _, fs in os.walk(out) for f in fs):
                break
            time.sleep(0.002)
        killed = first.poll() is None
        if killed:
            first.send_signal(signal.SIGKILL)
        first.wait()
        print(f"index 1: first pod {'killed part-way' if killed else 'finished before the kill'}")

        # The Job's pods, `parallelism` at a time (index 1 again: OnFailure restarts it).
        pending = list(range(completions))
        running = []
        while pending or running:
            while pending and len(running) < parallelism:
                index = pending.pop(0)
                running.append((index, pod.start(log, JOB_COMPLETION_INDEX=index)))
            index, process = running.pop(0)
            if process.wait() != 0:
                log.close()
                print(open(os.path.join(work, "pods.log")).read()[-3000:])
                fail(f"the pod of index {index} exited with {process.returncode}")
        # A pod of a finished index runs again (a node lost after it succeeded): the dataset's
        # files stay as they are (.shards/, the bookkeeping merge removes, records its seconds).
        before = tree_digest(out, skip=(".shards",))
        if pod.start(log, JOB_COMPLETION_INDEX=3).wait() != 0:
            fail("index 3 run again after it finished failed")
        if tree_digest(out, skip=(".shards",)) != before:
            fail("running index 3 again after it finished changed the output")
        log.close()

        merge = Pod(merge_job, exe, mounts)
        if merge.command[1:] != ["merge", out]:
            fail(f"the merge Job's command {merge.command[1:]} does not merge the shards' folder {out}")
        subprocess.run(merge.command, check=True, env=clean_environment(), stdout=subprocess.DEVNULL)
        expect_same_tree(single, out, f"the Indexed Job's {completions} pods, merged")

        # AWS Batch: an array job of 20 children, count from AWS_BATCH_JOB_ARRAY_SIZE.
        batch = os.path.join(work, "batch")
        recipe = os.path.join(work, "recipe", "recipe.yaml")
        for index in range(20):
            subprocess.run([exe, "generate", recipe, "--shard", "auto", "-o", batch, "--quiet",
                            "--cache", cache], check=True,
                           env=clean_environment(AWS_BATCH_JOB_ARRAY_INDEX=index,
                                                 AWS_BATCH_JOB_ARRAY_SIZE=20))
        subprocess.run([exe, "merge", batch], check=True, stdout=subprocess.DEVNULL,
                       env=clean_environment())
        expect_same_tree(single, batch, "an AWS Batch array job of 20, merged")

        # The errors: no task index, a Kubernetes pod without --shards, counts that disagree.
        for variables, extra, expected in (
                ({}, [], "no scheduler task index is set"),
                ({"JOB_COMPLETION_INDEX": 2}, [], "spec.completions"),
                ({"AWS_BATCH_JOB_ARRAY_INDEX": 2, "AWS_BATCH_JOB_ARRAY_SIZE": 3}, ["--shards", "4"],
                 "AWS_BATCH_JOB_ARRAY_SIZE=3 but --shards 4")):
            target = os.path.join(work, "refused")
            result = subprocess.run([exe, "generate", recipe, "--shard", "auto", "-o", target] +
                                    extra, env=clean_environment(**variables),
                                    capture_output=True, text=True)
            if result.returncode != 2 or expected not in result.stderr:
                fail(f"--shard auto with {variables} {extra}: exit {result.returncode}, "
                     f"{result.stderr!r}; expected exit 2 and {expected!r}")
            if os.path.exists(target):
                fail(f"--shard auto with {variables} {extra} was refused but wrote {target}")
            print(f"refused as it should be: {result.stderr.strip()}")
        print("PASS: the Indexed Job's pods and an AWS Batch array merge into a single run's bytes")
        return 0
    finally:
        shutil.rmtree(work, ignore_errors=True)


def main():
    if len(sys.argv) == 3 and sys.argv[1] == "schema":
        return check_schema(os.path.realpath(sys.argv[2]))
    if len(sys.argv) == 4 and sys.argv[1] == "run":
        return run_jobs(os.path.realpath(sys.argv[2]), os.path.realpath(sys.argv[3]))
    print(__doc__)
    return 2


if __name__ == "__main__":
    sys.exit(main())
