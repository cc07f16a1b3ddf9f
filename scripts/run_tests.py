#!/usr/bin/env python3
"""Runs `cargo test ARGS` with its test binaries side by side, as many at a time as the machine
has cores (ET_TEST_JOBS to choose): `cargo test` runs them one after another, and most of the
step's time went to binaries whose last long test held one core while the other idled.

Builds with `cargo test ARGS --no-run`, runs each test binary from its package's folder (as
cargo does) and then the doc tests (`cargo test ARGS --doc`) as one more job; prints each job's
output as it ends, then a table of the jobs by time, the slowest first. Exits 1 if any failed.

Usage: scripts/run_tests.py --workspace --features et-host/viewer
"""

import json
import os
import subprocess
import sys
import threading
import time


def test_binaries(args):
    """(name, executable, package folder) of every test binary `cargo test ARGS` runs, built."""
    out = subprocess.run(
        ["cargo", "test", *args, "--no-run", "--message-format=json-render-diagnostics"],
        stdout=subprocess.PIPE,
        check=True,
        text=True,
    ).stdout
    binaries = []
    for line in out.splitlines():
        msg = json.loads(line)
        if msg.get("reason") != "compiler-artifact" or not msg.get("executable"):
            continue
        if not msg["profile"]["test"]:
            continue
        folder = os.path.dirname(msg["manifest_path"])
        # Its source, from the workspace's root: host/learn/tests/unit/main.rs, et-core/src/lib.rs.
        name = os.path.relpath(msg["target"]["src_path"])
        binaries.append((name, [msg["executable"]], folder))
    return binaries


def main():
    args = sys.argv[1:]
    jobs_env = os.environ.get("ET_TEST_JOBS")
    jobs = int(jobs_env) if jobs_env else os.cpu_count() or 1
    # The doc tests last: cargo may wait there for a build beside this one (test.sh's Python
    # module) to release the target folder.
    queue = test_binaries(args) + [("doc tests", ["cargo", "test", *args, "--doc"], os.getcwd())]
    results = []
    lock = threading.Lock()
    started_all = time.monotonic()

    def worker():
        while True:
            with lock:
                if not queue:
                    return
                name, command, folder = queue.pop(0)
            started = time.monotonic()
            run = subprocess.run(
                command, cwd=folder, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True
            )
            seconds = time.monotonic() - started
            with lock:
                print(f"\n-- {name} ({seconds:.1f} s, exit {run.returncode})", flush=True)
                print(run.stdout.rstrip(), flush=True)
                results.append((seconds, name, run.returncode))

    threads = [threading.Thread(target=worker) for _ in range(max(1, jobs))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    wall = time.monotonic() - started_all
    print(f"\n{len(results)} test jobs, {jobs} at a time, in {wall:.0f} s:")
    for seconds, name, code in sorted(results, reverse=True):
        print(f"  {seconds:6.1f} s  {name}{'' if code == 0 else f'  FAILED (exit {code})'}")
    failed = [name for _, name, code in results if code != 0]
    if failed:
        print("failed: " + ", ".join(failed))
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
