#!/usr/bin/env python3
"""The example SSP system on libcosim (libcosimpy), checked against fmpy.

fmu/HydraulicSlewingPlate-osp.ssp (written by `hsp package`; the form of the example system
libcosim reads, without the system's own connectors) holds SystemStructure.ssd, the FMU and
the parameter set resources/complete.ssv (the FMU's default: the complete system with its
built-in 30 deg move). libcosim loads it with the set bound to the instance `plate`, reads the 10 ms
fixed step and the 6 s stop time from the .ssd, and runs it with the reference r at 0 V (the
preset's own move is the experiment);
its log level is lowered to errors (at its default it prints ~1000 debug lines). fmpy then runs
the same FMU with the values read from the same .ssv, the same step and the same input.
Prints the system; the set's switches (Integers in the FMI 2.0 description) as libcosim read them
back; y_pot [V] and p_load (final, peak) from both tools; their largest difference.
Run: .venv/bin/python examples/libcosim_ssp.py [--ssp SSP]
"""
import argparse
import pathlib
import tempfile
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
from fmpy import read_model_description, simulate_fmu
from libcosimpy.CosimExecution import CosimExecution
from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
from libcosimpy.CosimObserver import CosimObserver

ap = argparse.ArgumentParser()
ap.add_argument("--ssp", default=str(pathlib.Path(__file__).parents[1] / "fmu" / "HydraulicSlewingPlate-osp.ssp"))
ssp = ap.parse_args().ssp
SSD = "{http://ssp-standard.org/SSP1/SystemStructureDescription}"
with zipfile.ZipFile(ssp) as z:
    ssd = ET.fromstring(z.read("SystemStructure.ssd"))
    component = ssd.find(f".//{SSD}Component")  # the one FMU instance and its parameter set
    source = component.find(f".//{SSD}ParameterBinding").get("source")
    values = {p.get("name"): p[0] for p in ET.fromstring(z.read(source)).iter(
        "{http://ssp-standard.org/SSP1/SystemStructureParameterValues}Parameter")}
    fmu_bytes = z.read(component.get("source"))
kind = {"Real": float, "Integer": int, "Boolean": lambda v: v == "true"}
values = {n: kind[e.tag.split("}")[1]](e.get("value")) for n, e in values.items()}
R = 0.0  # the reference r [V]: the preset's built-in move alone
stop = float(ssd.find(f"{SSD}DefaultExperiment").get("stopTime"))
OSP = "{http://opensimulationplatform.com/SSP/OSPAnnotations}"
step = float(ssd.find(f".//{OSP}FixedStepAlgorithm").get("baseStepSize"))
print(f"system {ssd.get('name')}: instance {component.get('name')}, {source} ({len(values)} values), "
      f"0 to {stop:g} s at {step * 1e3:g} ms, r = {R:g} V")

log_output_level(CosimLogLevel.ERROR)
execution = CosimExecution.from_ssp_file(ssp)
plate = execution.slave_index_from_instance_name(component.get("name"))
refs = {v.name.decode(): v.reference for v in execution.slave_variables(plate)}
execution.real_initial_value(plate, refs["r"], R)
observer = CosimObserver.create_last_value()
execution.add_observer(observer)
cosim = []
for _ in range(round(stop / step)):
    assert execution.step()
    cosim.append(observer.last_real_values(plate, [refs["y_pot"], refs["p_load"]]))
cosim = np.array(cosim)
switches = {}  # filled below from the FMU's Integer variables the set holds

with tempfile.TemporaryDirectory() as d:  # fmpy runs the FMU the .ssp carries
    fmu = pathlib.Path(d) / "HydraulicSlewingPlate.fmu"
    fmu.write_bytes(fmu_bytes)
    integers = [v.name for v in read_model_description(str(fmu)).modelVariables if v.type == "Integer"]
    switches = {n: values[n] for n in values if n in integers}
    r = np.array([(0.0, R, 0, 0, 0), (stop, R, 0, 0, 0)],  # every input: r = R, the others 0
                 dtype=[(n, float) for n in ("time", "r", "e_in", "F1", "F2")])
    res = simulate_fmu(str(fmu), stop_time=stop, output_interval=step, input=r,
                       output=["y_pot", "p_load"], start_values=values)
read = observer.last_integer_values(plate, [refs[n] for n in switches])
print(f"libcosim reads back the set's switches {', '.join(f'{n} = {v}' for n, v in zip(switches, read))}: "
      f"as the set has them: {list(read) == list(switches.values())}")
ref = np.column_stack([res["y_pot"][1:], res["p_load"][1:]])
for name, x in [("libcosim", cosim), ("fmpy", ref)]:
    print(f"{name:9s} y_pot final {x[-1, 0]:.6f} V, peak {x[:, 0].max():.6f} V; "
          f"p_load final {x[-1, 1] / 1e5:.4f} bar, peak {np.abs(x[:, 1]).max() / 1e5:.4f} bar")
print(f"max |libcosim - fmpy| over {len(ref)} steps: y_pot {np.abs(cosim[:, 0] - ref[:, 0]).max():.1e} V, "
      f"p_load {np.abs(cosim[:, 1] - ref[:, 1]).max():.1e} Pa")
