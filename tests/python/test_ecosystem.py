"""The FMI ecosystem's formats in the packaged FMUs and in ssp/ (docs/ecosystem.md): the reference
results of the default experiment (the FMI-LS-REF manifest valid against its schema, every output
in the Reference FMUs' layout) reproduced by fmpy and libcosim as the manifest states, the presets as SSP 1.0 parameter sets valid against the SSP 1.0 schema, the
example SSP system run by libcosim agreeing with fmpy on the same parameter set, and the icon and
terminals (terminalsAndIcons.xml valid against FMI 3.0's schema, its members variables of the FMU).
"""

import io
import math
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET
import zipfile

import fmpy
import numpy as np
import pytest
import xmlschema
from fmpy import read_model_description, simulate_fmu
from fmpy.fmi2 import FMU2Slave
from fmpy.fmi3 import FMU3Slave
from fmpy.util import read_csv
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimObserver import CosimObserver
from libcosimpy.CosimSlave import CosimLocalSlave
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


def stated_without_stop_time(fmu):
    """What the manifest states for an importer that passes no stop time: the largest deviation
    relative to a column's largest magnitude, the same before the last points, and how many."""
    result = [r for r in manifest(fmu).iter("Related") if r.get("role") == "result"]
    found = re.search(r"one that passes no stop time \(libcosim\) reproduces the values within "
                      r"([0-9.eE+-]+) of each column's largest magnitude, and within ([0-9.eE+-]+) "
                      r"but at the last ([0-9]+) communication points", result[0].get("description"))
    assert found, result[0].get("description")
    return float(found.group(1)), float(found.group(2)), int(found.group(3))


def fmi_ls_ref_schema():
    """FMI-LS-REF's own schema (tests/schema/fmi-ls-ref/, its README says where from): the remote
    locations it imports and includes mapped to the copies beside it, no network."""
    folder = ROOT / "tests" / "schema" / "fmi-ls-ref"
    remote = "https://raw.githubusercontent.com/modelica/fmi-standard/main/schema/"
    return xmlschema.XMLSchema(
        str(folder / "fmi3LayeredStandardReferenceManifest.xsd"), allow="local",
        uri_mapper={remote + n: str(folder / n)
                    for n in ("fmi3LayeredStandardManifest.xsd", "fmi3Annotation.xsd")})


def manifest_text(fmu):
    with zipfile.ZipFile(fmu) as z:
        return z.read(f"{LS_REF}/fmi-ls-manifest.xml").decode()


@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
def test_manifest_is_valid_against_the_fmi_ls_ref_schema(fmus, version):
    fmi_ls_ref_schema().validate(manifest_text(fmus[version]))


def test_the_schema_refuses_a_manifest_without_the_ls_description(fmus):
    """The omission the Reference FMUs' manifests have (and ours had): the schema requires
    fmi-ls:fmi-ls-description."""
    text = manifest_text(fmus["fmi2"])
    without = re.sub(r'\s+fmi-ls:fmi-ls-description="[^"]*"', "", text, count=1)
    assert without != text
    assert not fmi_ls_ref_schema().is_valid(without)


@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
def test_documentation_has_the_page_fmi_ls_ref_recommends(fmus, version):
    """FMI-LS-REF recommends documentation/fmi-ls-ref.{txt|html} and a link to it from the main
    documentation; the page names every file the manifest lists."""
    with zipfile.ZipFile(fmus[version]) as z:
        page = z.read("documentation/fmi-ls-ref.html").decode()
        index = z.read("documentation/index.html").decode()
    assert 'href="fmi-ls-ref.html"' in index
    for r in manifest(fmus[version]).iter("Related"):
        assert f"<code>{r.get('source')}</code>" in page, r.get("source")


def output_columns(fmu):
    """The result's columns as the Reference FMUs write them: every output of the model
    description in its order, and how many values each cell holds (an FMI 3.0 array's size)."""
    md = read_model_description(fmu)
    return [(v.name, math.prod(int(d.start) for d in v.dimensions) if v.dimensions else 1)
            for v in md.modelVariables if v.causality == "output"]


def shipped_result(fmu):
    """The result's text and the table fmpy's read_csv (the Reference FMUs' reader) makes of it."""
    with zipfile.ZipFile(fmu) as z:
        text = z.read(RESULT).decode()
    with tempfile.TemporaryDirectory() as d:
        path = pathlib.Path(d) / "result.csv"
        path.write_text(text)
        return text, read_csv(path)


@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
def test_shipped_result_holds_every_output_and_no_input_in_the_reference_fmus_layout(fmus, version):
    text, ref = shipped_result(fmus[version])
    columns = output_columns(fmus[version])
    assert text.splitlines()[0].split(",") == ["time"] + [n for n, _ in columns]
    for name, size in columns:
        assert ref[name].shape[1:] == ((size,) if size > 1 else ()), name
    if version == "fmi2":
        assert [f"acc[{k}]" for k in range(1, 13)] == [n for n, _ in columns if n.startswith("acc[")]
    else:
        assert ("acc", 12) in columns
    md = read_model_description(fmus[version])
    de = md.defaultExperiment
    grid = np.arange(round(float(de.stopTime) / float(de.stepSize)) + 1) * float(de.stepSize)
    np.testing.assert_allclose(ref["time"], grid, rtol=0, atol=1e-12)


@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
def test_shipped_result_is_the_committed_reference_of_hsp_run(fmus, version):
    """Two runs of the default experiment on the same FMU: `hsp package`'s, which records every
    output, and `hsp run`'s, which tests/default_experiment.rs checks writes
    tests/reference/default_experiment.csv to the byte. The outputs both hold agree to the bit."""
    _, ref = shipped_result(fmus[version])
    committed = read_csv(ROOT / "tests" / "reference" / "default_experiment.csv")
    shared = [n for n in committed.dtype.names if n in ref.dtype.names and n != "time"]
    assert len(shared) >= 20, shared
    assert np.array_equal(committed["time"], ref["time"])
    for n in shared:
        assert np.array_equal(committed[n], ref[n]), n


def step_the_grid(fmu, version, stop_time_passed):
    """The default experiment stepped through fmpy's low-level API, the stop time passed to the
    FMU or not: every output at every communication point, as read_csv reads the result."""
    md = read_model_description(fmu)
    de = md.defaultExperiment
    stop, step, tol = float(de.stopTime), float(de.stepSize), float(de.tolerance)
    outputs = [v for v in md.modelVariables if v.causality == "output"]
    unzipped = fmpy.extract(fmu)
    cls = FMU2Slave if version == "fmi2" else FMU3Slave
    slave = cls(guid=md.guid, unzipDirectory=unzipped,
                modelIdentifier=md.coSimulation.modelIdentifier, instanceName="reference")
    slave.instantiate()
    stop_arg = stop if stop_time_passed else None
    if version == "fmi2":
        slave.setupExperiment(tolerance=tol, startTime=0.0, stopTime=stop_arg)
        slave.enterInitializationMode()
    else:
        slave.enterInitializationMode(tolerance=tol, startTime=0.0, stopTime=stop_arg)
    slave.exitInitializationMode()

    def row(t):
        values = [t]
        for v in outputs:
            size = math.prod(int(d.start) for d in v.dimensions) if v.dimensions else 1
            if v.type in ("Real", "Float64"):
                got = (slave.getReal([v.valueReference]) if version == "fmi2"
                       else slave.getFloat64([v.valueReference], nValues=size))
            else:
                got = (slave.getInteger([v.valueReference]) if version == "fmi2"
                       else slave.getInt32([v.valueReference], nValues=size))
            values.append(tuple(got) if size > 1 else got[0])
        return tuple(values)

    n = round(stop / step)
    rows = [row(0.0)]
    for k in range(n):
        t, t_next = k * step, (stop if k + 1 == n else (k + 1) * step)
        slave.doStep(t, t_next - t)
        rows.append(row(t_next))
    slave.terminate()
    slave.freeInstance()
    shutil.rmtree(unzipped, ignore_errors=True)
    sizes = {v.name: (math.prod(int(d.start) for d in v.dimensions) if v.dimensions else 1)
             for v in outputs}
    dtype = [("time", np.float64)] + [(v.name, np.float64, (sizes[v.name],)) if sizes[v.name] > 1
                                      else (v.name, np.float64) for v in outputs]
    return np.array(rows, dtype=dtype)


def deviations(got, ref, names, rows=slice(None)):
    """Each column's largest deviation from the result in the rows `rows` over the column's
    largest magnitude."""
    worst = {}
    for n in names:
        scale = np.max(np.abs(ref[n]))
        dev = np.max(np.abs(got[n][rows] - ref[n][rows]))
        worst[n] = dev / scale if scale > 0 else dev
    return worst


def check_without_stop_time(fmu, got, ref, names, who):
    """`got` (the rows after t = 0 of `ref` when `ref` is longer) as the manifest states for an
    importer that passes no stop time; prints the largest deviation."""
    bound, before, points = stated_without_stop_time(fmu)
    assert before <= bound <= stated_tolerance(fmu)
    ref = ref[len(ref) - len(got):]
    for what, worst, stated in (("", deviations(got, ref, names), bound),
                                (f" before the last {points} points",
                                 deviations(got, ref, names, slice(0, -points)), before)):
        name = max(worst, key=worst.get)
        print(f"{who} without a stop time: largest deviation / column peak{what}", worst[name],
              "in", name)
        assert worst[name] <= stated, (name, worst[name])


@pytest.mark.parametrize("version", ["fmi2", "fmi3"])
def test_the_stated_reproduction_holds_with_and_without_a_stop_time(fmus, version):
    """What the manifest states: fmpy's simulate_fmu (which passes the stop time) and fmpy's
    low-level API passing it reproduce every column to the bit; without a stop time the result
    holds to the bit up to the stated last points, and there within the stated bound."""
    fmu = fmus[version]
    _, ref = shipped_result(fmu)
    names = [n for n in ref.dtype.names if n != "time"]
    md = read_model_description(fmu)
    de = md.defaultExperiment
    res = simulate_fmu(fmu, fmi_type="CoSimulation", start_time=float(de.startTime),
                       stop_time=float(de.stopTime), output_interval=float(de.stepSize),
                       relative_tolerance=float(de.tolerance), output=names)
    assert np.array_equal(res["time"], ref["time"])
    with_stop = deviations(res, ref, names)
    assert max(with_stop.values()) == 0, {n: w for n, w in with_stop.items() if w}
    assert max(deviations(step_the_grid(fmu, version, True), ref, names).values()) == 0
    check_without_stop_time(fmu, step_the_grid(fmu, version, False), ref, names, version)


def test_libcosim_without_a_stop_time_reproduces_the_result_as_stated(fmu_path, md):
    """libcosim 0.0.6 passes no stop time to fmi2SetupExperiment: every Real output after each of
    its steps on the default experiment's grid as the manifest states."""
    _, ref = shipped_result(fmu_path)
    de = md.defaultExperiment
    n = round(float(de.stopTime) / float(de.stepSize))
    reals = [v for v in md.modelVariables if v.causality == "output" and v.type == "Real"]
    execution = CosimExecution.from_step_size(step_size=round(float(de.stepSize) * 1e9))
    plate = execution.add_local_slave(CosimLocalSlave(fmu_path=fmu_path, instance_name="plate"))
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    refs = [v.valueReference for v in reals]
    rows = []
    for _ in range(n):
        assert execution.step()
        rows.append(tuple(observer.last_real_values(slave_index=plate, variable_references=refs)))
    got = np.array(rows, dtype=[(v.name, np.float64) for v in reals])
    check_without_stop_time(fmu_path, got, ref, [v.name for v in reals], "libcosim")


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
