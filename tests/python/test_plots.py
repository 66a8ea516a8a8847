"""The plots of `hsp`: `hsp run` writes PNG and SVG beside its CSV (not with --no-plot), `hsp frf
--plot` a Bode plot; the files are real, non-trivial pictures."""

import xml.etree.ElementTree as ET

from conftest import hsp
from figures import assert_png, assert_svg, png_size


def test_run_writes_png_and_svg_beside_the_csv(fmu_path, tmp_path):
    csv = tmp_path / "step.csv"
    out = hsp("run", "--no-build", "--fmu", fmu_path, "--csv", str(csv), "--stop", "0.3")
    png, svg = csv.with_suffix(".png"), csv.with_suffix(".svg")
    assert csv.exists() and png.exists() and svg.exists(), out
    assert str(png) in out and str(svg) in out, out
    w, h = assert_png(png.read_bytes())
    # One panel per quantity recorded (at least command, angle, pressure): a tall figure.
    assert w == 1000 and h >= 3 * 170, (w, h)
    root = assert_svg(svg.read_bytes())
    texts = " ".join("".join(t.itertext()) for t in root.iter() if t.tag.endswith("text"))
    assert "time [s]" in texts and "angle [deg]" in texts, texts


def test_no_plot_writes_only_the_csv(fmu_path, tmp_path):
    csv = tmp_path / "quiet.csv"
    hsp("run", "--no-build", "--fmu", fmu_path, "--csv", str(csv), "--stop", "0.05", "--no-plot")
    assert csv.exists()
    assert not csv.with_suffix(".png").exists() and not csv.with_suffix(".svg").exists()


def test_frf_plot_is_a_bode_plot_with_peaks_and_table_1(tmp_path):
    stem = tmp_path / "bode"
    # The LOES driving hub and plate (Fig. 9b): the three bending peaks of Table 1.
    out = hsp("frf", "--input", "r", "--output", "w_tip", "--preset", "paper-fig9b",
              "--plot", str(stem) + ".png")
    png, svg = stem.with_suffix(".png"), stem.with_suffix(".svg")
    assert png.exists() and svg.exists(), out
    assert png_size(png.read_bytes()) == (1000, 700)
    assert_png(png.read_bytes())
    root = assert_svg(svg.read_bytes())
    texts = " ".join("".join(t.itertext()) for t in root.iter() if t.tag.endswith("text"))
    # The peaks the command prints are labelled on the plot, and the paper's reference is there.
    peaks = [line.split()[0] for line in out.splitlines()[2:] if line.strip() and not line.startswith("wrote")]
    assert len(peaks) == 3, out
    for f in peaks:
        assert f"{float(f):.2f} Hz" in texts, (f, texts)
    assert "Table 1" in texts and "magnitude [dB]" in texts and "phase [deg]" in texts


def test_frf_plot_has_no_table_1_marks_off_the_plate(tmp_path):
    stem = tmp_path / "motor"
    hsp("frf", "--input", "r", "--output", "y_pot", "--plot", str(stem))
    root = ET.parse(stem.with_suffix(".svg")).getroot()
    texts = " ".join("".join(t.itertext()) for t in root.iter() if t.tag.endswith("text"))
    assert "magnitude [dB]" in texts
    assert "Table 1" not in texts


def test_modes_plot_labels_each_shape_with_its_frequency(tmp_path):
    import json

    stem = tmp_path / "modes"
    out = json.loads(hsp("modes", "--plot", str(stem), "--count", "6"))
    png, svg = stem.with_suffix(".png"), stem.with_suffix(".svg")
    assert png_size(png.read_bytes()) == (1100, 2 * 260 + 60)  # 6 shapes: 2 rows of 3
    assert_png(png.read_bytes())
    root = assert_svg(svg.read_bytes())
    texts = " ".join("".join(t.itertext()) for t in root.iter() if t.tag.endswith("text"))
    for label, f in list(zip(out["labels"], out["f_hz"]))[:6]:
        assert f"{label}  {f:.2f} Hz" in texts or f"{label} {f:.2f} Hz" in texts, (label, f, texts)
