#!/usr/bin/env python3
"""The Slurm executor on a real single-node Slurm cluster on localhost.

Brings the cluster up with tests/slurm/local_cluster.sh (Debian's munge,
slurmctld, slurmd and slurm-client), then:

1. runs the smoke study with the local executor and with the Slurm executor
   and checks that report.json and metrics.csv are the same;
2. runs it again through Slurm into a fresh folder, cancels a running array
   task with scancel, and checks that the report job resubmitted exactly the
   renders that task had not finished, that nothing else was rendered twice,
   and that the report is again the local one;

and stops the cluster by the PIDs it started. Prints the wall times of the
local and the Slurm runs (a figure for the notes, not a timed assertion).
Exit 77 (a skip for CTest) only when the Slurm packages are missing.

Usage: test_slurm_executor.py PENUMBRA_BINARY SOURCE_DIR
"""

import json
import os
import shutil
import subprocess
import sys
import tempfile
import time

PENUMBRA, SOURCE = sys.argv[1], sys.argv[2]
STUDY = os.path.join(SOURCE, "scenes/studies/smoke.json")
CLUSTER = os.path.join(SOURCE, "tests/slurm/local_cluster.sh")
CHAIN_LIMIT_S = 600


def fail(message):
    print(f"FAIL: {message}", flush=True)
    sys.exit(1)


def run(argv, env, check=True):
    p = subprocess.run(argv, env=env, capture_output=True, text=True, timeout=CHAIN_LIMIT_S)
    if check and p.returncode != 0:
        fail(f"{' '.join(argv)} exited {p.returncode}:\n{p.stdout}\n{p.stderr}")
    return p


def our_jobs(env):
    p = run(["squeue", "-h", "-o", "%i %j %T"], env, check=False)
    return [line.split() for line in p.stdout.splitlines() if "penumbra" in line]


def wait_for_chain(folder, env):
    """Waits until no Penumbra job is queued or running; the report is then final."""
    start = time.monotonic()
    while our_jobs(env):
        if time.monotonic() - start > CHAIN_LIMIT_S:
            fail(f"the Slurm chain of {folder} did not end in {CHAIN_LIMIT_S} s")
        time.sleep(0.5)
    if not os.path.exists(os.path.join(folder, "report.json")):
        logs = os.path.join(folder, "slurm", "logs")
        tails = ""
        for name in sorted(os.listdir(logs)):
            with open(os.path.join(logs, name), errors="replace") as f:
                tails += f"--- {name}\n" + "".join(f.readlines()[-8:])
        fail(f"the chain ended without {folder}/report.json; logs:\n{tails}")


def without_provenance(path):
    """report.json's content less its provenance (date, machine), which
    differs between any two runs; anything else must match."""
    with open(path, encoding="utf-8") as f:
        doc = json.load(f)
    doc.pop("provenance", None)
    return doc


def same_outputs(a, b):
    if without_provenance(os.path.join(a, "report.json")) != \
            without_provenance(os.path.join(b, "report.json")):
        fail(f"report.json of {b} differs from the local executor's ({a}) beyond its provenance")
    with open(os.path.join(a, "metrics.csv"), "rb") as fa, \
            open(os.path.join(b, "metrics.csv"), "rb") as fb:
        if fa.read() != fb.read():
            fail(f"metrics.csv of {b} differs from the local executor's ({a})")


def batches(folder):
    out = []
    d = os.path.join(folder, "slurm")
    for name in sorted(os.listdir(d)):
        if name.startswith("batch-") and name.endswith(".json"):
            with open(os.path.join(d, name)) as f:
                out.append(json.load(f))
    return out


def cache_entries(folder):
    """Finished entries: KEY.exr. A hidden ".KEY.penumbra-tmp.HOST.PID.N.exr"
    is a render being written (or left by the task scancel killed, which the
    next run removes): not an entry."""
    d = os.path.join(folder, "cache")
    return {n[:-4]: os.stat(os.path.join(d, n)).st_mtime_ns
            for n in os.listdir(d) if n.endswith(".exr") and not n.startswith(".")}


def task_keys(folder, task_id):
    """The keys of array task "123_4", from the batch file of array job 123."""
    array, index = task_id.split("_")
    for b in batches(folder):
        if b["array_job"] == array:
            return b, int(index), set(task_entry_keys(b, int(index)))
    return None, None, set()


def task_entry_keys(batch, task):
    first, count = batch["tasks"][task]
    return [j["key"] for j in batch["jobs"][first:first + count]]


def cancel_a_running_task(folder, env):
    """scancel an array task once it has cached some but not all of its
    renders; returns its batch, its index and the cache entries present once
    it has ended."""
    start = time.monotonic()
    while time.monotonic() - start < CHAIN_LIMIT_S:
        for job_id, name, state in our_jobs(env):
            if name != "penumbra-render" or state != "RUNNING" or "_" not in job_id:
                continue
            batch, index, keys = task_keys(folder, job_id)
            done = keys & set(cache_entries(folder))
            if batch and 0 < len(done) < len(keys):
                run(["scancel", job_id], env)
                while any(j[0] == job_id for j in our_jobs(env)):
                    time.sleep(0.1)
                return batch, index, cache_entries(folder)
        time.sleep(0.05)
    fail("no array task was caught between its first and its last render")


def killed_task_check(local, folder, env):
    p = run([PENUMBRA, "run", STUDY, "-o", folder, "--executor", "slurm", "--renders-per-task",
             "6", "--array-limit", "1"], env)
    print(p.stdout.strip(), flush=True)
    batch, task, present = cancel_a_running_task(folder, env)
    wait_for_chain(folder, env)
    killed = set(task_entry_keys(batch, task))
    unfinished = killed - set(present)
    # A render submitted twice is one the killed task did not finish; later
    # convergence rounds submit new renders, never an earlier batch's again.
    seen, resubmitted = set(), set()
    for b in batches(folder):
        keys = {j["key"] for j in b["jobs"]}
        resubmitted |= keys & seen
        seen |= keys
    if resubmitted != unfinished:
        fail(f"resubmitted {sorted(resubmitted)}, expected the killed task's unfinished "
             f"{sorted(unfinished)}")
    after = cache_entries(folder)
    redone = [k for k, t in present.items() if after.get(k) != t]
    if redone:
        fail(f"renders finished before the scancel were rendered again: {redone}")
    same_outputs(local, folder)
    print(f"scancel of task {task}: {len(unfinished)} unfinished renders resubmitted and "
          f"rendered, {len(present)} finished ones kept", flush=True)


def main():
    work = tempfile.mkdtemp(prefix="penumbra-slurm-")
    cluster = os.path.join(work, "cluster")
    up = subprocess.run(["bash", CLUSTER, "start", cluster])
    if up.returncode == 77:
        print("SKIP: the Slurm packages are missing (apt-get install munge slurmctld slurmd "
              "slurm-client)")
        sys.exit(77)
    if up.returncode != 0:
        fail("the local Slurm cluster did not start")
    env = dict(os.environ, SLURM_CONF=os.path.join(cluster, "slurm.conf"))
    try:
        local = os.path.join(work, "local")
        t0 = time.monotonic()
        run([PENUMBRA, "run", STUDY, "-o", local, "--jobs", "2", "-q"], env)
        t_local = time.monotonic() - t0

        folder = os.path.join(work, "slurm")
        t0 = time.monotonic()
        p = run([PENUMBRA, "run", STUDY, "-o", folder, "--executor", "slurm"], env)
        print(p.stdout.strip(), flush=True)
        wait_for_chain(folder, env)
        t_slurm = time.monotonic() - t0
        same_outputs(local, folder)
        # The truths' convergence runs inside array tasks (a chain per
        # variant), with the external renders: one submission, one report job.
        arrays = [b["array_job"] for b in batches(folder)]
        if len(arrays) != 1:
            fail(f"the smoke study took {len(arrays)} submissions ({arrays}), expected one")
        chains = sum(1 for j in batches(folder)[0]["jobs"] if "chain" in j)
        if chains != 4:
            fail(f"{chains} convergence chains submitted, expected one per variant (4)")
        print(f"smoke study: local executor {t_local:.1f} s, Slurm executor {t_slurm:.1f} s "
              f"({t_slurm / t_local:.2f}x) on this one-node cluster; report.json and "
              f"metrics.csv identical", flush=True)
        status = run([PENUMBRA, "status", folder], env)
        print(status.stdout.strip(), flush=True)

        killed_task_check(local, os.path.join(work, "killed"), env)
    finally:
        subprocess.run(["bash", CLUSTER, "stop", cluster])
    shutil.rmtree(work, ignore_errors=True)
    print("PASS", flush=True)


if __name__ == "__main__":
    main()
