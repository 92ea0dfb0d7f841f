#!/usr/bin/env python3
"""The Kubernetes example's commands, run here without a cluster (CTest examples.kubernetes).

Takes the container command of examples/kubernetes/study-job.yaml and runs it once per completion index with
JOB_COMPLETION_INDEX set, as the Indexed Job's pods would; then merge-job.yaml's command; then checks that the
merged rows equal an unsharded run's in every deterministic column and that the report exists. The manifests'
paths are mapped onto this machine: /opt/qdmr (the image's sources) to the checkout, the results volume's
mountPath to a temporary folder, `qdmr` to the build's executable; the spec is swapped for the small test study
(STUDY_SPEC) so the test takes seconds. The command itself is the manifest's, word for word.

  kubernetes_study_test.py QDMR SOURCE_DIR
"""
import os
import shutil
import subprocess
import sys
import tempfile

import yaml

IMAGE_SOURCES = "/opt/qdmr"  # where examples/kubernetes/Containerfile puts the checkout
TEST_SPEC = "/opt/qdmr/tests/report/small_study.json"


def container(manifest):
    spec = manifest["spec"]["template"]["spec"]
    assert spec["restartPolicy"] == "Never", "a failed shard must fail its pod (the Job retries it)"
    (c,) = spec["containers"]
    mounts = {m["name"]: m["mountPath"] for m in c.get("volumeMounts", [])}
    claims = {v["name"]: v["persistentVolumeClaim"]["claimName"] for v in spec.get("volumes", [])}
    assert set(mounts) == set(claims), "every mount is a volume of the pod"
    return c, mounts


def run(c, mounts, work, bin_dir, extra_env):
    """Runs the container's command with its env, the paths mapped onto this machine."""
    def mapped(value):
        for mount in mounts.values():
            if value == mount or value.startswith(mount + "/"):
                return os.path.join(work, "volume") + value[len(mount):]
        if value.startswith(IMAGE_SOURCES + "/"):
            return os.path.join(SOURCE, value[len(IMAGE_SOURCES) + 1:])
        return value

    env = dict(os.environ, PATH=bin_dir + os.pathsep + os.environ["PATH"])
    for e in c.get("env", []):
        env[e["name"]] = mapped(e["value"])
    env.update({k: mapped(v) for k, v in extra_env.items()})
    return subprocess.run(c["command"] + c.get("args", []), env=env, cwd=work, capture_output=True, text=True)


def main(qdmr, source):
    global SOURCE
    SOURCE = source
    with open(os.path.join(source, "examples/kubernetes/study-job.yaml")) as f:
        study = yaml.safe_load(f)
    with open(os.path.join(source, "examples/kubernetes/merge-job.yaml")) as f:
        merge = yaml.safe_load(f)
    job = study["spec"]
    assert job["completionMode"] == "Indexed", "the shard comes from JOB_COMPLETION_INDEX of an Indexed Job"
    shards = job["completions"]
    c, mounts = container(study)
    env = {e["name"]: e["value"] for e in c["env"]}
    assert int(env["SHARDS"]) == shards, f"SHARDS ({env['SHARDS']}) must equal completions ({shards})"
    merge_c, merge_mounts = container(merge)
    assert merge_mounts == mounts, "the merge job mounts the shards' volume where they wrote it"
    merge_env = {e["name"]: e["value"] for e in merge_c["env"]}
    assert merge_env["RESULTS"] == env["RESULTS"], "the merge job reads the folder the shards wrote"

    work = tempfile.mkdtemp(prefix="qdmr-k8s-")
    try:
        bin_dir = os.path.join(work, "bin")
        os.makedirs(bin_dir)
        os.symlink(os.path.realpath(qdmr), os.path.join(bin_dir, "qdmr"))
        os.makedirs(os.path.join(work, "volume"))
        for index in range(shards):
            done = run(c, mounts, work, bin_dir, {"JOB_COMPLETION_INDEX": str(index), "STUDY_SPEC": TEST_SPEC})
            if done.returncode != 0:
                print(f"pod {index} failed ({done.returncode}):\n{done.stdout}{done.stderr}", file=sys.stderr)
                return 1
        done = run(merge_c, merge_mounts, work, bin_dir, {})
        if done.returncode != 0:
            print(f"the merge pod failed ({done.returncode}):\n{done.stdout}{done.stderr}", file=sys.stderr)
            return 1
        results = os.path.join(work, "volume", env["RESULTS"][len(mounts["results"]) + 1:])
        for shard in range(1, shards + 1):
            assert os.path.isfile(os.path.join(results, f"shard-{shard}", "study.json")), f"shard {shard} missing"
        assert os.path.isfile(os.path.join(results, "report", "index.html")), "no report"
        whole = os.path.join(work, "unsharded")
        subprocess.run([qdmr, "study", os.path.join(source, "tests/report/small_study.json"), "-o", whole],
                       check=True, capture_output=True)
        same = subprocess.run([sys.executable, os.path.join(source, "tests/examples/same_study_rows.py"),
                               os.path.join(results, "merged", "results.json"), os.path.join(whole, "results.json")])
        if same.returncode != 0:
            return 1
        print(f"kubernetes: {shards} indexed pods, merge and report: ok")
        return 0
    finally:
        shutil.rmtree(work, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main(*sys.argv[1:3]))
