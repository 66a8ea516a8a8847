"""The FMI ecosystem's formats in the packaged FMUs and in ssp/ (docs/ecosystem.md): the reference
results of the default experiment (FMI-LS-REF layout) reproduced by fmpy within the tolerance the
manifest states, the presets as SSP 1.0 parameter sets valid against the SSP 1.0 schema, the
example SSP system run by libcosim agreeing with fmpy on the same parameter set, and the icon and
terminals (terminalsAndIcons.xml valid against FMI 3.0's schema, its members variables of the FMU).
"""

import io
import math
import pathlib
import re
import subprocess
import sys
import xml.etree.ElementTree as ET
import zipfile

import fmpy
import numpy as np
import pytest
import xmlschema
from fmpy import read_model_description, simulate_fmu
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimObserver import CosimObserver
from PIL import Image

from conftest import ROOT, _presets, read_ssv

LS_REF = "extra/org.fmi-standard.fmi-ls-ref"
RESULT = f"{LS_REF}/HydraulicSlewingPlate_out.csv"
FMU3 = ROOT / "fmu" / "fmi3" / "HydraulicSlewingPlate.fmu"
SSP = ROOT / "fmu" / "HydraulicSlewingPlate.ssp"  # SSP's form: the system's connectors
OSP = ROOT / "fmu" / "HydraulicSlewingPlate-osp.ssp"  # libcosim's and ecos's: the component's
SSP_SCHEMA = pathlib.Path(fmpy.__file__).parent / "ssp" / "schema"
FMI3_SCHEMA = pathlib.Path(fmpy.__file__).parent / "schema" / "fmi3"


@pytest.fixture(scope="session")
def fmus(fmu_path):
    """Both FMUs (`hsp package` writes the FMI 3.0 one and the .ssp beside the FMI 2.0 one)."""
    return {"fmi2": fmu_path, "fmi3": str(FMU3)}


def manifest(fmu):
    with zipfile.ZipFile(fmu) as z:
        return ET.fromstring(z.read(f"{LS_REF}/fmi-ls-manifest.xml"))


def stated_tolerance(fmu):
    """The relative tolerance the manifest states for comparing with the result."""
    result = [r for r in manifest(fmu).iter("Related") if r.get("role") == "result"]
    assert len(result) == 1
    found = re.search(r"within a relative tolerance of ([0-9.eE+-]+) of its largest magnitude",
                      result[0].get("description"))
    assert found, result[0].get("description")
    return float(found.group(1))


@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
def test_manifest_lists_the_result_and_every_preset_and_nothing_else(fmus, version):
    root = manifest(fmus[version])
    assert root.tag == "fmiReferences"
    ns = "{http://fmi-standard.org/fmi-ls-manifest}"
    assert root.get(f"{ns}fmi-ls-name") == "org.fmi-standard.fmi-ls-ref"
    with zipfile.ZipFile(fmus[version]) as z:
        in_folder = {n[len(LS_REF) + 1:] for n in z.namelist() if n.startswith(LS_REF + "/")}
    listed = {r.get("source"): r.get("role") for r in root.iter("Related")}
    assert listed == {"HydraulicSlewingPlate_out.csv": "result",
                      **{f"{name}.ssv": "parameter" for name in _presets()}}
    assert in_folder == set(listed) | {"fmi-ls-manifest.xml"}
    md = read_model_description(fmus[version])
    assert stated_tolerance(fmus[version]) == float(md.defaultExperiment.tolerance)


@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
def test_shipped_result_is_the_committed_reference(fmus, version):
    """One result: the CSV in the FMU is `hsp run`'s on the packaged FMU, and
    tests/default_experiment.rs checks that run against the same committed file."""
    with zipfile.ZipFile(fmus[version]) as z:
        shipped = z.read(RESULT)
    assert shipped == (ROOT / "tests" / "reference" / "default_experiment.csv").read_bytes()


@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
def test_fmpy_reproduces_the_shipped_result_within_the_stated_tolerance(fmus, version):
    fmu = fmus[version]
    with zipfile.ZipFile(fmu) as z:
        ref = np.genfromtxt(io.BytesIO(z.read(RESULT)), delimiter=",", names=True, deletechars="")
    md = read_model_description(fmu)
    de = md.defaultExperiment
    names = [n for n in ref.dtype.names if n != "time"]
    start, stop, step, tol = (float(v) for v in (de.startTime, de.stopTime, de.stepSize,
                                                  de.tolerance))
    res = simulate_fmu(fmu, fmi_type="CoSimulation", start_time=start, stop_time=stop,
                       output_interval=step, relative_tolerance=tol, output=names)
    np.testing.assert_allclose(res["time"], ref["time"], rtol=0, atol=1e-12)
    rtol = stated_tolerance(fmu)
    worst = {}
    for n in names:
        scale = np.max(np.abs(ref[n]))
        worst[n] = np.max(np.abs(res[n] - ref[n])) / scale if scale > 0 else np.max(np.abs(res[n]))
    print(version, "largest deviation / column peak:", max(worst.values()))
    bad = {n: w for n, w in worst.items() if not w <= rtol}
    assert not bad, bad


def ssp_files():
    return sorted((ROOT / "ssp").rglob("*.ss[dv]"))


@pytest.mark.parametrize("path", ssp_files(), ids=lambda p: str(p.relative_to(ROOT / "ssp")))
def test_ssp_files_are_valid_ssp_1_0(path):
    xsd = {".ssv": "SystemStructureParameterValues.xsd",
           ".ssd": "SystemStructureDescription.xsd"}[path.suffix]
    schema = xmlschema.XMLSchema(str(SSP_SCHEMA / xsd))
    errors = list(schema.iter_errors(str(path)))
    assert not errors, errors[0]


def test_parameter_sets_are_the_presets(fmus):
    """Each .ssv (in ssp/ and in both FMUs) holds exactly its preset's settings (hsp presets
    --json), each with the type of its variable."""
    presets = _presets()
    assert {p.stem for p in (ROOT / "ssp" / "resources").glob("*.ssv")} == set(presets)
    for name, settings in presets.items():
        texts = [(ROOT / "ssp" / "resources" / f"{name}.ssv").read_bytes()]
        for fmu in fmus.values():
            with zipfile.ZipFile(fmu) as z:
                texts.append(z.read(f"{LS_REF}/{name}.ssv"))
        assert texts[1] == texts[0] and texts[2] == texts[0], name
        values = read_ssv(texts[0])
        assert values == settings, name
        assert all(type(values[k]) is type(v) for k, v in settings.items()), name


def example_system():
    root = ET.parse(ROOT / "ssp" / "SystemStructure.ssd").getroot()
    ns = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription"}
    (binding,) = root.iterfind(".//ssd:ParameterBinding", ns)
    experiment = root.find("ssd:DefaultExperiment", ns)
    step = float(root.find(".//{http://opensimulationplatform.com/SSP/OSPAnnotations}"
                           "FixedStepAlgorithm").get("baseStepSize"))
    return binding.get("source"), float(experiment.get("stopTime")), step


@pytest.mark.parametrize("archive,ssd", [(SSP, "SystemStructure.ssd"), (OSP, "osp/SystemStructure.ssd")],
                         ids=["ssp", "osp"])
def test_ssp_archive_holds_the_system_the_fmu_and_its_parameter_set(fmu_path, archive, ssd):
    source, _, _ = example_system()
    with zipfile.ZipFile(archive) as z:
        assert sorted(z.namelist()) == sorted(["SystemStructure.ssd", source,
                                               "resources/HydraulicSlewingPlate.fmu"])
        assert z.read("SystemStructure.ssd") == (ROOT / "ssp" / ssd).read_bytes()
        assert z.read(source) == (ROOT / "ssp" / source).read_bytes()
        assert z.read("resources/HydraulicSlewingPlate.fmu") == pathlib.Path(fmu_path).read_bytes()


def test_the_two_forms_differ_only_in_the_systems_connectors():
    """The libcosim/ecos form is SSP's with the system's <Connectors> and <Connections> taken out."""
    exposed = (ROOT / "ssp" / "SystemStructure.ssd").read_text()
    osp = (ROOT / "ssp" / "osp" / "SystemStructure.ssd").read_text()
    ns = {"ssd": "http://ssp-standard.org/SSP1/SystemStructureDescription"}
    system = ET.fromstring(exposed).find("ssd:System", ns)
    inputs = {c.get("name") for c in system.iterfind("ssd:Connectors/ssd:Connector", ns) if c.get("kind") == "input"}
    assert inputs == {"r", "e_in", "F1", "F2"}
    # Every input of the component is connected from the system (fmpy's runner needs that).
    ends = {(c.get("endElement"), c.get("endConnector")) for c in system.iterfind("ssd:Connections/ssd:Connection", ns)}
    assert {("plate", n) for n in inputs} <= ends
    stripped = re.sub(r"    <ssd:Connectors>.*?</ssd:Connectors>\n", "", exposed, count=1, flags=re.S)
    stripped = re.sub(r"    <ssd:Connections>.*?</ssd:Connections>\n", "", stripped, flags=re.S)
    assert stripped == osp


def test_fmpy_runs_the_example_system_and_its_move(fmu_path):
    """fmpy's SSP runner opens fmu/HydraulicSlewingPlate.ssp (every input connected from the
    system) and runs the bound preset, the FMU's defaults (the runner does not apply a system's
    parameter bindings): the 30 deg move, as fmpy runs the FMU itself, every output point up to
    the last (the runner passes no stop time)."""
    from fmpy.ssp.simulation import simulate_ssp

    _, stop, step = example_system()
    res = simulate_ssp(str(SSP), stop_time=stop, step_size=step)
    names = ["y_pot", "theta_motor", "p_load", "theta_hub", "acc_tip"]
    ref = simulate_fmu(fmu_path, stop_time=stop, output_interval=step, output=names)
    # The runner records the connectors after each step under the step's start time, and its
    # summed time takes one step more than the grid (601 rows to 6 s): row k is time (k + 1) h.
    assert len(res) >= len(ref) - 1
    res = res[:len(ref) - 2]
    assert abs(math.degrees(res["theta_hub"][-1]) - 30.0) < 0.1, math.degrees(res["theta_hub"][-1])
    assert abs(math.degrees(ref["theta_hub"][-1]) - 30.0) < 0.1
    for n in names:
        assert np.array_equal(res[n], res[f"plate.{n}"]), n
        span = np.ptp(ref[n])
        d = np.max(np.abs(res[n] - ref[n][1:-1]))
        assert d <= 1e-7 * span, (n, d, span)


def test_libcosim_runs_the_ssp_as_fmpy_runs_the_same_parameter_set(fmu_path, vr):
    """libcosim loads the -osp.ssp (the FMU with the parameter set bound); the test adds a 1 V step of
    r. fmpy runs the FMU with the values read from the same .ssv and the same step."""
    source, stop, step = example_system()
    values = read_ssv((ROOT / "ssp" / source).read_bytes())
    execution = CosimExecution.from_ssp_file(str(OSP))
    plate = execution.slave_index_from_instance_name("plate")
    assert plate is not None
    execution.real_initial_value(plate, vr["r"], 1.0)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    refs = [vr["y_pot"], vr["p_load"]]
    steps = round(stop / step)
    got = []
    for _ in range(steps):
        assert execution.step()
        got.append(observer.last_real_values(slave_index=plate, variable_references=refs))
    got = np.array(got)

    def fmpy_run(start_values):
        inp = np.array([(0.0, 1.0), (stop, 1.0)], dtype=[("time", np.float64), ("r", np.float64)])
        return simulate_fmu(fmu_path, stop_time=stop, output_interval=step, input=inp,
                            output=["y_pot", "p_load"], start_values=start_values)

    ref = fmpy_run(values)
    print("libcosim - fmpy before the last point: y_pot",
          np.max(np.abs(got[:-1, 0] - ref["y_pot"][1:-1])), "V, p_load",
          np.max(np.abs(got[:-1, 1] - ref["p_load"][1:-1])), "Pa; at the last: y_pot",
          abs(got[-1, 0] - ref["y_pot"][-1]), "V, p_load", abs(got[-1, 1] - ref["p_load"][-1]), "Pa")
    # The tolerances of tests/python/test_libcosim.py: the same FMU, the same steps. Up to the last
    # point: fmpy passes the stop time, so there the FMU ends a step on it, where libcosim (no stop
    # time) gets the dense output of a step that runs past it; both are within the solver's
    # tolerance of the solution (rtol 1e-6 of the range).
    np.testing.assert_allclose(got[:-1, 0], ref["y_pot"][1:-1], rtol=0, atol=1e-9)
    np.testing.assert_allclose(got[:-1, 1], ref["p_load"][1:-1], rtol=1e-9, atol=1e-3)
    for k, name in enumerate(["y_pot", "p_load"]):
        span = np.ptp(ref[name])
        assert abs(got[-1, k] - ref[name][-1]) < 1e-6 * span, (name, got[-1, k], ref[name][-1])


def test_icons_are_the_same_png_in_both_fmus(fmus):
    with zipfile.ZipFile(fmus["fmi2"]) as two, zipfile.ZipFile(fmus["fmi3"]) as three:
        png2 = two.read("model.png")
        png3 = three.read("terminalsAndIcons/icon.png")
        assert "terminalsAndIcons/icon.png" not in two.namelist()
        assert "model.png" not in three.namelist()
    assert png2 == png3
    image = Image.open(io.BytesIO(png2))
    assert image.format == "PNG" and image.size == (200, 200)
    # A picture, not a blank: the plate's blue and the sensors' red are there.
    colours = {c for _, c in image.convert("RGB").getcolors(maxcolors=1 << 16)}
    assert (176, 204, 232) in colours and (200, 30, 30) in colours


def test_terminals_are_valid_fmi3_and_name_variables_of_the_fmu(fmus):
    with zipfile.ZipFile(fmus["fmi3"]) as z:
        text = z.read("terminalsAndIcons/terminalsAndIcons.xml")
    schema = xmlschema.XMLSchema(str(FMI3_SCHEMA / "fmi3TerminalsAndIcons.xsd"))
    errors = list(schema.iter_errors(io.BytesIO(text)))
    assert not errors, errors[0]
    names = {v.name for v in read_model_description(fmus["fmi3"]).modelVariables}
    terminals = {t.get("name"): [m.get("variableName") for m in t.iter("TerminalMemberVariable")]
                 for t in ET.fromstring(text).iter("Terminal")}
    assert terminals == {"drive": ["r", "e_in"], "shakers": ["F1", "F2"],
                         "accelerometers": ["acc"], "hub": ["theta_hub", "omega_hub"],
                         "motor": ["y_pot", "theta_motor", "omega_motor", "p_load"]}
    assert all(m in names for members in terminals.values() for m in members)


def test_fmutool_reads_the_terminals(fmus):
    fmutool = pathlib.Path(sys.executable).parent / "fmutool"
    run = subprocess.run([str(fmutool), "-input", fmus["fmi3"], "-summary"], capture_output=True,
                         text=True)
    out = run.stdout + run.stderr
    assert run.returncode == 0, out
    for line in ["drive (2 signals", "shakers (2 signals", "accelerometers (1 signals",
                 "hub (2 signals", "motor (4 signals"]:
        assert line in out, out
