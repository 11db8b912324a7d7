"""The closing summary of scripts/test: test cases, not test programs.

    python3 tests/summary.py RESULTS_DIR [--stages FILE]

RESULTS_DIR holds JUnit XML files: CTest's (one per ctest run; a GoogleTest
case is one CTest test), pytest's (one per pytest suite, named after the
CTest test that ran it) and scripts/fuzz's (fuzz*.xml, a case per target). A CTest test that ran a pytest suite counts as that
suite's cases; if the suite wrote no XML (it crashed), as one failure.
Prints the failed and skipped cases with their reasons and ends with

    tests: N passed, N failed, N skipped (GoogleTest N, pytest N, fuzz targets N,
    other checks N)

Exit status 1 if a case failed, or, in CI (CI=true), if a case was skipped
because something was missing ("missing:" reasons: ../shared, the checker,
a host, a Python dependency that the setup installs)."""
import os
import sys
import xml.etree.ElementTree as ET
from pathlib import Path


def gtest_skip_reason(output):
    """The message of a GTEST_SKIP: the line after GoogleTest's
    'file:line: Skipped'."""
    lines = output.splitlines()
    for i, line in enumerate(lines[:-1]):
        if line.endswith(": Skipped"):
            return lines[i + 1].strip()
    return ""


def cases(xml_path):
    """(name, outcome, message) of every test case of a JUnit file; outcome
    is passed, failed or skipped."""
    root = ET.parse(xml_path).getroot()
    for case in root.iter("testcase"):
        name = f"{case.get('classname', '')}::{case.get('name')}".strip(":")
        status = case.get("status")  # CTest's attribute: run, fail, notrun, disabled
        failure = case.find("failure")
        if failure is None:
            failure = case.find("error")
        skipped = case.find("skipped")
        if failure is not None or status == "fail":
            message = failure.get("message", "") if failure is not None else ""
            yield name, "failed", (message or "").strip()
        elif skipped is not None or status in ("notrun", "disabled"):
            message = skipped.get("message", "") if skipped is not None else status
            output = case.findtext("system-out") or ""
            if message == "SKIP_REGULAR_EXPRESSION_MATCHED":  # a GTEST_SKIP: its own words
                message = gtest_skip_reason(output) or message
            elif message.startswith("SKIP_RETURN_CODE"):  # a check that said why on its way out
                message = next((line for line in output.splitlines() if line.startswith("missing")), message)
            yield name, "skipped", (message or "").strip()
        else:
            yield name, "passed", ""


def collect(results):
    pytest_files = {p.stem: p for p in results.glob("pytest/*.xml")}
    outcomes = []  # (kind, name, outcome, message)
    for ctest_xml in sorted(results.glob("ctest-*.xml")):
        for name, outcome, message in cases(ctest_xml):
            test = name.split("::")[-1]
            if test in pytest_files:
                continue  # counted from its own XML below
            if test.startswith(("python_", "integration_", "corpus_", "gui_", "hosts_", "walkthrough_")):
                # A pytest suite that left no XML: it did not get to its cases.
                outcomes.append(("pytest", test, "failed" if outcome != "skipped" else outcome,
                                 message or "the suite wrote no results (crashed or timed out)"))
            else:  # a GoogleTest case (Suite.Case), or a check of its own (docs_…)
                outcomes.append(("gtest" if "." in test else "check", test, outcome, message))
    for stem, path in sorted(pytest_files.items()):
        try:
            for name, outcome, message in cases(path):
                outcomes.append(("pytest", f"{stem}: {name}", outcome, message))
        except ET.ParseError as e:
            outcomes.append(("pytest", stem, "failed", f"unreadable results: {e}"))
    for fuzz_xml in sorted(results.glob("fuzz*.xml")):
        try:
            for name, outcome, message in cases(fuzz_xml):
                outcomes.append(("fuzz", name, outcome, message))
        except ET.ParseError as e:
            outcomes.append(("fuzz", fuzz_xml.stem, "failed", f"unreadable results: {e}"))
    return outcomes


def main():
    results = Path(sys.argv[1])
    outcomes = collect(results)
    ci = os.environ.get("CI") == "true"
    failed = [o for o in outcomes if o[2] == "failed"]
    skipped = [o for o in outcomes if o[2] == "skipped"]
    required = [o for o in skipped if ci and o[3].startswith("missing")]
    if failed:
        print("failed:")
        for kind, name, _, message in failed:
            print(f"  {name}: {message.splitlines()[0][:200] if message else ''}")
    if skipped:
        print("skipped:" + (" (a missing piece fails in CI)" if required else ""))
        by_reason = {}
        for kind, name, _, message in skipped:
            by_reason.setdefault(message, []).append(name)
        for message, names in sorted(by_reason.items(), key=lambda kv: -len(kv[1])):
            shown = ", ".join(names[:3]) + (f" and {len(names) - 3} more" if len(names) > 3 else "")
            print(f"  {len(names)} x {message or 'no reason given'}: {shown}")
    passed = sum(1 for o in outcomes if o[2] == "passed")
    kinds = {k: sum(1 for o in outcomes if o[0] == k) for k in ("gtest", "pytest", "fuzz", "check")}
    print(f"tests: {passed} passed, {len(failed) + len(required)} failed, {len(skipped) - len(required)} skipped "
          f"(GoogleTest {kinds['gtest']}, pytest {kinds['pytest']}, fuzz targets {kinds['fuzz']}, "
          f"other checks {kinds['check']})")
    return 1 if failed or required or not outcomes else 0


if __name__ == "__main__":
    sys.exit(main())
