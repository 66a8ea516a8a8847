"""The user documentation (README.md and docs/*.md) names the tests behind what it calls tested:
every test file it names exists, and every test function it names is defined in a test. A renamed
or deleted test then fails here instead of leaving the documentation pointing at nothing."""

import pathlib
import re

ROOT = pathlib.Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def defined_in(text):
    """The test and function names a source defines (tests/contract_both_versions.rs defines its
    tests through its macro: `both_versions!(name, ...)`)."""
    return (set(re.findall(r"\bdef (\w+)", text)) | set(re.findall(r"\bfn (\w+)", text))
            | set(re.findall(r"\bboth_versions!\(\s*(\w+)", text)))


def test_named_test_files_exist():
    missing = []
    for page in PAGES:
        for path in set(re.findall(r"\btests/[\w/]+\.(?:rs|py|c|sh)\b", page.read_text())):
            if not (ROOT / path).exists():
                missing.append(f"{page.relative_to(ROOT)}: {path}")
    assert not missing, missing


def test_named_test_functions_exist():
    # A test is named in backticks after its file: "`tests/servo_valve_model.rs`,
    # `coupled_power_balance_at_random_states`" or "`test_simulation.py`
    # (`test_step_response_matches_analytic_closed_loop`)". Each backticked snake_case name of
    # four words or more, or starting with test_, within 300 characters after a test file's name
    # must be defined in that file (a trailing * stands for a common prefix); a pytest name must
    # be defined in some file of tests/python.
    python = {n for f in ROOT.glob("tests/python/*.py") for n in defined_in(f.read_text())}
    files = {f.name: f for f in [*ROOT.glob("tests/*.rs"), *ROOT.glob("tests/python/*.py")]}
    everything = {n for f in ROOT.glob("src/**/*.rs") for n in defined_in(f.read_text())}
    missing, checked = [], 0
    for page in PAGES:
        text = page.read_text()
        mentions = [(m.end(), m.group(1)) for m in re.finditer(r"\b(\w+\.(?:rs|py))\b", text)]
        for m in re.finditer(r"`((?:\w+::)*[a-z0-9]+(?:_[a-z0-9]+){3,}\*?|test_\w+)`", text):
            name = m.group(1)
            leaf = name.split("::")[-1]
            before = [f for end, f in mentions if 0 <= m.start() - end <= 300 and f in files]
            if before:
                pool = defined_in(files[before[-1]].read_text()) | (everything if "::" in name else set())
            elif leaf.startswith("test_"):
                pool = python
            else:
                continue
            checked += 1
            ok = any(d.startswith(leaf[:-1]) for d in pool) if leaf.endswith("*") else leaf in pool
            if not ok:
                missing.append(f"{page.relative_to(ROOT)}: {name} (looked in {before[-1] if before else 'tests/python'})")
    assert checked > 40, checked  # the pages do name tests
    assert not missing, missing
