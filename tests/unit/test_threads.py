"""The command line runs BLAS on one thread per process unless the user chose a count
(palpbayes.threads): measured 11.7 s against 3.7 s for one `palpbayes fit` on a two-core
machine with its other core busy."""

from __future__ import annotations

import json
import os
import subprocess
import sys

from palpbayes.threads import BLAS_VARIABLES

CODE = """
import json, os
from threadpoolctl import threadpool_info
from palpbayes.threads import BLAS_VARIABLES, one_blas_thread
changed = one_blas_thread()
blas = [p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"]
print(json.dumps({"changed": changed, "blas": blas,
                  "env": {v: os.environ.get(v) for v in BLAS_VARIABLES}}))
"""


def _run(env_extra: dict) -> dict:
    env = {k: v for k, v in os.environ.items() if k not in BLAS_VARIABLES}
    env.update(env_extra)
    out = subprocess.run([sys.executable, "-c", CODE], env=env, capture_output=True,
                         text=True, check=True)
    return json.loads(out.stdout)


def test_one_thread_for_this_process_and_its_workers():
    got = _run({})
    assert got["changed"] is True
    assert got["blas"] and all(n == 1 for n in got["blas"])
    assert all(v == "1" for v in got["env"].values())  # the processes it starts


def test_a_count_the_user_set_is_kept():
    got = _run({"OMP_NUM_THREADS": "2"})
    assert got["changed"] is False
    assert got["env"]["OMP_NUM_THREADS"] == "2" and got["env"]["OPENBLAS_NUM_THREADS"] is None


def test_the_command_line_calls_it():
    import palpbayes.cli as cli

    assert cli.one_blas_thread.__module__ == "palpbayes.threads"
