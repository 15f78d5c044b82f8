"""Mutation driver of ``python-minimalist-package`` (run by graders/python_minimalist_package.py).

argv[1]: a JSON list of patches (Python statements over ``C``, the learner's
``MinimalistClass``; see mutants.yaml). Runs the learner's unittest suite
(``test/`` of the working directory) once unbroken, as a control, then once per
patch, each in a forked child so one broken class never leaks into the next
run. Prints one JSON list, one ``[tests run, passed?(, error)]`` per run.
"""

import io
import json
import os
import sys
import unittest

sys.path.insert(0, ".")
PATCHES = json.loads(sys.argv[1])


def run_suite(patch):
    """[tests run, passed?] of the suite with ``patch`` applied to the class (in this process)."""
    try:
        sys.stdout = sys.stderr = io.StringIO()
        from minimalist_package import MinimalistClass as C  # noqa: PLC0415 - the learner's package, imported after output is captured
        exec(patch, {"C": C})
        suite = unittest.defaultTestLoader.discover("test")
        result = unittest.TextTestRunner(stream=io.StringIO(), verbosity=0).run(suite)
        return [result.testsRun, result.wasSuccessful()]
    except BaseException as exc:  # the learner's tests or class failed to load: say how
        return [0, False, type(exc).__name__ + ": " + str(exc)]


results = []
for patch in ["", *PATCHES]:
    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(read)
        os.write(write, json.dumps(run_suite(patch)).encode())
        os._exit(0)
    os.close(write)
    data = b""
    while chunk := os.read(read, 65536):
        data += chunk
    os.close(read)
    os.waitpid(pid, 0)
    results.append(json.loads(data.decode() or "[0, false]"))
print(json.dumps(results))
