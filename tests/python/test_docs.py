"""The FMU's documentation page: it holds the figures, every file it references is in the FMU, the
figures are real pictures, the tables print numbers short, the FMU still validates, and a real
browser (headless Chromium) renders it with every image loaded and no request leaving the
machine."""

import html
import html.parser
import json
import re
import shutil
import subprocess
import xml.etree.ElementTree as ET
import zipfile

import pytest
from fmpy.validation import validate_fmu

from conftest import hsp, page_requests
from figures import assert_png, assert_svg

FIGURES = ["sketch.svg", "bond_graph.svg", "default_experiment.svg", "bode.svg"]


class References(html.parser.HTMLParser):
    """Every src and href of a page."""

    def __init__(self):
        super().__init__()
        self.refs = []

    def handle_starttag(self, tag, attrs):
        for k, v in attrs:
            if k in ("src", "href") and v is not None:
                self.refs.append((tag, v))


@pytest.fixture(scope="module")
def archive(fmu_path):
    with zipfile.ZipFile(fmu_path) as z:
        return {name: z.read(name) for name in z.namelist()}


@pytest.fixture(scope="module")
def page(archive):
    return archive["documentation/index.html"].decode()


def test_the_page_holds_the_figures_and_every_reference_is_in_the_fmu(archive, page):
    parser = References()
    parser.feed(page)
    refs = [v for _, v in parser.refs]
    for figure in FIGURES:
        assert figure in refs, figure
    for ref in refs:
        assert not re.match(r"^[a-z]+:", ref), f"external reference {ref}"
        assert f"documentation/{ref}" in archive, f"{ref} is referenced but not in the FMU"
    # Nothing loaded from elsewhere by CSS either.
    assert "url(" not in page and "@import" not in page


def test_figures_are_real_pictures(archive):
    for name in FIGURES:
        assert_svg(archive[f"documentation/{name}"], min_texts=5)
    assert_png(archive["documentation/default_experiment.png"], min_width=800)
    assert_png(archive["documentation/bode.png"], min_width=800)


def test_bond_graph_shows_the_models_elements(archive, page):
    """The figure is the model's own graph: every element `hsp graph` prints for the settings the
    caption names is drawn exactly once (as a node titled with its name), grouped as the paper
    draws it, and nothing is left outside the groups."""
    svg = archive["documentation/bond_graph.svg"].decode()
    root = ET.fromstring(svg)
    tag = lambda e: e.tag.split("}")[-1]
    titles = [e.text for e in root.iter() if tag(e) == "title"]
    texts = [e.text for e in root.iter() if tag(e) == "text"]
    caption = page[page.index('<img src="bond_graph.svg"'):]
    caption = caption[:caption.index("</figcaption>")]
    settings = re.findall(r"<code>([\w.]+) = ([^<]+)</code>", caption)
    assert ("hydraulics.model", "2") in settings, settings
    args = [a for k, v in settings for a in ("--set", f"{k}={v}")]
    names = re.findall(r'^  e\d+ \[label=.*, tooltip="([^"]*)"\];$', hsp("graph", *args), re.M)
    assert len(names) > 50, len(names)
    for name in names:
        assert titles.count(name) == 1, (name, titles.count(name))
    for group in ("BG1 ", "BG2 ", "BG3 ", "Torsion bar", "Hub", "Plate modes", "Signal part"):
        assert any(t.startswith(group) for t in texts), group
    assert "Other elements" not in texts
    # The consistent formulation: each mode's inertia on its absolute rate (a 0-junction fed by
    # the hub through a TF), the structure's modal dashpots.
    for name in ("plate.I[1]", "plate.I[1].rate", "plate.I[1].hub_tf", "plate.C[1]",
                 "plate.damping[1]", "torsion_bar.k"):
        assert name in titles, name


def test_page_content(page, md):
    # How to use, expected result with numbers, FMI interfaces, platforms, version, full reference.
    for text in ("How to use", "fmpy", "Simulink", "Modelica", "Expected result", "Co-Simulation",
                 "linux64", "FMU version", md.version, "Barbosa", "CONEM", "2002",
                 "before initialisation only", "read-only"):
        assert text in page, text
    # The expected result: what `hsp run` printed for the default experiment, with its numbers.
    pre = re.search(r"What <code>hsp run</code> printed.*?<pre>(.*?)</pre>", page, re.S)
    assert pre, "no expected result"
    assert re.search(r"final\s+-?\d", pre.group(1)) and re.search(r"solver\s+\d+ steps", pre.group(1)), pre.group(1)
    # Every parameter and output is in a table, with its unit and display unit.
    for v in md.modelVariables:
        assert f"<code>{v.name}</code>" in page.replace("&quot;", '"'), v.name
    assert "bar" in page and "deg" in page
    # Values printed short: no long float reprs in the tables.
    assert not re.search(r"\d\.\d{8,}", page), re.search(r".{40}\d\.\d{8,}.{20}", page)
    # The reader has neither this repository nor its notes.
    assert "README" not in page and "MODEL_NOTES" not in page


def test_fmu_still_validates(fmu_path):
    assert validate_fmu(fmu_path) == []


CHECK = """<script>
window.addEventListener("load", () => {
  const images = [...document.images].map(i =>
    i.getAttribute("src") + "=" + (i.complete && i.naturalWidth > 0 ? "ok" : "broken"));
  document.body.setAttribute("data-check",
    JSON.stringify({images, height: document.body.scrollHeight}));
});
</script></body>"""


def test_chromium_renders_every_image_and_requests_nothing_outside(archive, tmp_path):
    chromium = shutil.which("chromium") or shutil.which("chromium-browser")
    assert chromium, "headless Chromium is needed (tests/setup.sh installs Debian's chromium)"
    doc = tmp_path / "documentation"
    doc.mkdir()
    for name, data in archive.items():
        if name.startswith("documentation/"):
            (tmp_path / name).parent.mkdir(parents=True, exist_ok=True)
            (tmp_path / name).write_bytes(data)
    page = (doc / "index.html").read_text()
    assert page.count("</body>") == 1
    (doc / "check.html").write_text(page.replace("</body>", CHECK))
    flags = [chromium, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
             "--disable-component-update", "--disable-sync", "--no-first-run",
             f"--user-data-dir={tmp_path / 'profile'}", "--virtual-time-budget=10000"]
    net_log = tmp_path / "net.json"
    dom = subprocess.run(flags + [f"--log-net-log={net_log}", "--dump-dom", (doc / "check.html").as_uri()],
                         capture_output=True, text=True, timeout=120).stdout
    m = re.search(r'data-check="([^"]*)"', dom)
    assert m, dom[-2000:]
    check = json.loads(html.unescape(m.group(1)))
    assert sorted(i.split("=")[0] for i in check["images"]) == sorted(FIGURES), check["images"]
    assert all(i.endswith("=ok") for i in check["images"]), check["images"]
    assert page_requests(net_log) == []
    assert check["height"] > 3000, check["height"]  # figures and tables laid out, not an empty page
    # And a screenshot of the top of the page: a real picture.
    shot = tmp_path / "page.png"
    subprocess.run(flags + [f"--screenshot={shot}", "--window-size=1200,2400",
                            (doc / "index.html").as_uri()], capture_output=True, timeout=120)
    assert_png(shot.read_bytes(), min_width=1200, min_height=2400, min_bytes=50_000)
