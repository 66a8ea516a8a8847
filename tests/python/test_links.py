"""Every link of the project's markdown pages leads somewhere: a relative link names a file or
folder of the repository (tracked, or one the build writes and .gitignore lists), and a link with
a #section names a heading of its target page (GitHub's anchors: lower case, punctuation but
hyphens and underscores dropped, spaces as hyphens, a repeated heading numbered -1, -2, ...).
A quoted section name ("see "Interfaces" in the README") is checked the same way where the page
says it is a section of another page. External links (http, https, mailto) are not fetched: the
machines have no network."""

import pathlib
import re
import subprocess
from collections import Counter

import pytest

from conftest import ROOT

PAGES = sorted({"README.md", "CONTRIBUTING.md", "fmu/README.md", "examples/README.md",
                *(str(p.relative_to(ROOT)) for p in (ROOT / "docs").glob("*.md")),
                *(str(p.relative_to(ROOT)) for p in (ROOT / "bench").glob("*.md"))})
# [text](target) and [text]: target, outside code; images too.
INLINE = re.compile(r"!?\[(?:[^\]\[]|\[[^\]]*\])*\]\(\s*<?([^)\s>]+)>?(?:\s+\"[^\"]*\")?\s*\)")
REFERENCE = re.compile(r"^\s{0,3}\[[^\]]+\]:\s*<?(\S+?)>?(?:\s+\"[^\"]*\")?\s*$", re.M)
# Files the build writes (not tracked; .gitignore lists them): a page may link to them.
BUILT = {"fmu/HydraulicSlewingPlate.fmu", "fmu/fmi3/HydraulicSlewingPlate.fmu",
         "fmu/HydraulicSlewingPlate.ssp", "docs/web/hsp.wasm", "docs/web/hsp.wasm.js",
         "results/default_experiment.csv", "results/default_experiment.png"}


def without_code(text):
    """The page without fenced code blocks and inline code spans (links there are not links)."""
    text = re.sub(r"^(```|~~~).*?^\1[^\n]*$", "", text, flags=re.M | re.S)
    return re.sub(r"`[^`\n]*`", "", text)


def slug(heading):
    """GitHub's anchor of a heading's text."""
    text = re.sub(r"<[^>]+>", "", heading)                  # inline HTML
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", text)  # links keep their text
    text = text.replace("`", "").strip().lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(page):
    """The anchors of a markdown page's headings (numbered as GitHub numbers repeats)."""
    seen, found = Counter(), set()
    text = re.sub(r"^(```|~~~).*?^\1[^\n]*$", "", page.read_text(), flags=re.M | re.S)
    for m in re.finditer(r"^#{1,6}\s+(.+?)\s*#*\s*$", text, re.M):
        base = slug(m.group(1))
        found.add(base if seen[base] == 0 else f"{base}-{seen[base]}")
        seen[base] += 1
    found |= set(re.findall(r"<a\s+(?:name|id)=\"([^\"]+)\"", text))
    return found


def tracked():
    out = subprocess.run(["git", "ls-files", "--cached", "--others", "--exclude-standard"],
                         cwd=ROOT, capture_output=True, text=True, check=True).stdout.split()
    files = set(out)
    folders = {str(p) for f in files for p in pathlib.PurePosixPath(f).parents}
    return files | folders | BUILT


def links(page):
    text = without_code((ROOT / page).read_text())
    return INLINE.findall(text) + REFERENCE.findall(text)


def test_the_checker_finds_links_and_anchors(tmp_path):
    page = tmp_path / "p.md"
    page.write_text("# A `code` title: one, two\n## Again\n## Again\n```\n# not a heading\n```\n")
    assert anchors(page) == {"a-code-title-one-two", "again", "again-1"}
    assert slug("Known limits") == "known-limits"
    assert slug("The command-line tool `hsp`") == "the-command-line-tool-hsp"
    text = "See [a](docs/x.md#y) and ![i](img/p.png \"t\") but not `[c](nope.md)`.\n[r]: other.md\n"
    assert INLINE.findall(without_code(text)) == ["docs/x.md#y", "img/p.png"]
    assert REFERENCE.findall(without_code(text)) == ["other.md"]


@pytest.mark.parametrize("page", PAGES)
def test_every_link_leads_somewhere(page):
    files = tracked()
    base = (ROOT / page).parent
    broken = []
    for target in links(page):
        if re.match(r"^[a-z][a-z0-9+.-]*:", target):
            continue  # http, https, mailto: not fetched
        path, _, section = target.partition("#")
        resolved = (base / path).resolve() if path else (ROOT / page).resolve()
        try:
            name = str(resolved.relative_to(ROOT))
        except ValueError:
            broken.append(f"{target}: outside the repository")
            continue
        if path and name not in files:
            broken.append(f"{target}: no such file")
            continue
        if section:
            if not name.endswith(".md"):
                continue
            if section not in anchors(ROOT / name):
                broken.append(f"{target}: no section #{section} in {name}")
    assert not broken, f"{page}:\n  " + "\n  ".join(broken)


@pytest.mark.parametrize("page", PAGES)
def test_quoted_sections_of_the_readme_exist(page):
    """'see "X" in the (project's) README' names a section the README has."""
    text = without_code((ROOT / page).read_text())
    readme = anchors(ROOT / "README.md")
    missing = [name for name in re.findall(r"\"([^\"]+)\" in the (?:project's )?README", text)
               if slug(name) not in readme]
    assert not missing, f"{page} names README sections that do not exist: {missing}"
