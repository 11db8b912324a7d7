"""The test tiers without ../shared: outside CI every suite still collects
(its cases that need ../shared skip, saying "missing: ..."), the benchmarks'
smoke run skips with CTest's skip status and says why, and tests/summary.py
lists that reason; in CI (CI=true) each of them fails instead."""
import os
import subprocess
import sys

import pytest

from conftest import ROOT

SUITES = sorted((ROOT / "tests" / "integration").glob("test_*.py")) + sorted(
    (ROOT / "tests" / "python").glob("test_*.py"))
SKIP_RETURN_CODE = 77  # benchmarks/CMakeLists.txt gives it to CTest


def without_shared(tmp_path, ci):
    """The environment of a run whose ../shared is missing."""
    env = {k: v for k, v in os.environ.items() if k != "CI"}
    env.update(MESHMEND_SHARED_DIR=str(tmp_path / "no-shared"), PYTHONDONTWRITEBYTECODE="1")
    if ci:
        env["CI"] = "true"
    return env


@pytest.mark.parametrize("suite", SUITES, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_every_suite_collects_without_shared(suite, tmp_path):
    """A skip outside a test (at import) is a collection error: the suite
    would fail instead of listing its cases as skipped."""
    run = subprocess.run([sys.executable, "-m", "pytest", "--collect-only", "-q", "-p", "no:cacheprovider",
                          suite.name], cwd=suite.parent, env=without_shared(tmp_path, ci=False),
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-2000:]
    assert " collected" in run.stdout, run.stdout[-1000:]


def test_benchmarks_skip_without_shared_and_fail_in_ci(tmp_path):
    for ci, status, words in ((False, SKIP_RETURN_CODE, "missing: "), (True, 1, "missing in CI: ")):
        run = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "run.py"), "all", "--smoke"],
                             env=without_shared(tmp_path, ci), capture_output=True, text=True, timeout=120)
        assert run.returncode == status, (ci, run.stdout, run.stderr)
        assert words + str(tmp_path / "no-shared" / "data") in run.stdout + run.stderr, (ci, run.stdout, run.stderr)


JUNIT = """<?xml version="1.0" encoding="UTF-8"?>
<testsuite name="(empty)" tests="2" failures="0" disabled="0" skipped="1" hostname="" time="0">
  <testcase name="benchmarks_smoke" classname="benchmarks_smoke" time="0.1" status="notrun">
    <skipped message="SKIP_RETURN_CODE=77"/>
    <system-out>missing: /nowhere/shared/data (the benchmarks' meshes live in ../shared)
</system-out>
  </testcase>
  <testcase name="Predicates.Orient" classname="Predicates.Orient" time="0.1" status="run">
    <system-out>ok</system-out>
  </testcase>
</testsuite>
"""


@pytest.mark.parametrize("ci", [False, True])
def test_summary_gives_a_skipped_checks_reason_and_fails_it_in_ci(tmp_path, ci):
    (tmp_path / "ctest-all.xml").write_text(JUNIT)
    run = subprocess.run([sys.executable, str(ROOT / "tests" / "summary.py"), str(tmp_path)],
                         env=without_shared(tmp_path, ci), capture_output=True, text=True, timeout=60)
    assert "1 x missing: /nowhere/shared/data (the benchmarks' meshes live in ../shared): benchmarks_smoke" \
        in run.stdout, run.stdout
    if ci:
        assert run.returncode == 1 and "tests: 1 passed, 1 failed, 0 skipped" in run.stdout, run.stdout
    else:
        assert run.returncode == 0 and "tests: 1 passed, 0 failed, 1 skipped" in run.stdout, run.stdout
