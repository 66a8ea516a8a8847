#!/usr/bin/env python3
"""The FMI 3.0 FMU's WebAssembly component, run by Wasmtime, against the native binary.

What it shows
    The FMI 3.0 FMU carries, beside its native binaries, `binaries/wasm32-wasip2/
    HydraulicSlewingPlate.wasm`: the model as a WebAssembly component after the draft FMI layered
    standard for WebAssembly (fmi-ls-wasm, https://github.com/modelica/fmi-ls-wasm), with the
    manifest `extra/org.modelica.fmi-ls-wasm/manifest.xml`. This script is a small fmi-ls-wasm
    importer: it loads the component with the Bytecode Alliance's Wasmtime (the `wasmtime`
    package from PyPI, its component-model API), links the draft's `callbacks` interface and
    WASI 0.2, and drives the draft's `co-simulation` and `model-exchange` interfaces. Beside it,
    fmpy drives the native FMI 3.0 library of the same FMU with the same calls. It prints:
    - the default experiment (6 s at 5 ms points, the FMU's tolerance) in Co-Simulation: every
      output at every point, the largest |difference| as a fraction of the output's range, and
      how many of the values are the same doubles;
    - a saved FMU state carried across: a state saved by the component at 3 s, restored into the
      native library, and both run on to 6 s;
    - Model Exchange at the start: the states, their nominals and derivatives, and the
      derivatives at perturbed states;
    - what each run cost (wall time, one run each: an indication, not a benchmark).

How to run (from the repository root, after `cargo run --release --bin hsp -- package` with the
`wasm32-wasip2` Rust target installed, as `bash tests/setup.sh` does):
    .venv/bin/python examples/wasm_component.py [--fmu3 fmu/fmi3/HydraulicSlewingPlate.fmu]
docs/platforms.md quotes one run; tests/python/test_wasm_component.py checks it.
"""

import argparse
import ctypes
import pathlib
import shutil
import time
import zipfile
import xml.etree.ElementTree as ET

import numpy as np
import wasmtime
import wasmtime.component as wc
from fmpy import extract, read_model_description
from fmpy.fmi3 import FMU3Model, FMU3Slave

ROOT = pathlib.Path(__file__).resolve().parents[1]
FMU3 = ROOT / "fmu" / "fmi3" / "HydraulicSlewingPlate.fmu"
COMPONENT = "binaries/wasm32-wasip2/HydraulicSlewingPlate.wasm"
MANIFEST = "extra/org.modelica.fmi-ls-wasm/manifest.xml"
PACKAGE = "fmi:fmi3/{}@3.0.0"


class Component:
    """The FMU's component instantiated in a Wasmtime store, with the draft's imports linked:
    `callbacks.log-message` appends (instance, status, category, message) to `self.log`."""

    def __init__(self, wasm_bytes):
        self.engine = wasmtime.Engine()
        self.store = wasmtime.Store(self.engine)
        self.store.set_wasi(wasmtime.WasiConfig())
        component = wc.Component(self.engine, wasm_bytes)
        linker = wc.Linker(self.engine)
        linker.add_wasip2()
        self.log = []
        with linker.root() as root:
            with root.add_instance(PACKAGE.format("callbacks")) as callbacks:
                callbacks.add_func("log-message",
                                   lambda _store, *message: self.log.append(message))
                for name in ("clock-update", "lock-preemption", "unlock-preemption"):
                    callbacks.add_func(name, lambda _store: None)
            with root.add_instance(PACKAGE.format("intermediate-update-callbacks")) as updates:
                updates.add_func("intermediate-update", lambda _store, *_: (False, 0.0))
        self.instance = linker.instantiate(self.store, component)

    def function(self, interface, name):
        iface = self.instance.get_export_index(self.store, PACKAGE.format(interface))
        index = self.instance.get_export_index(self.store, name, iface)
        if index is None:
            raise KeyError(f"the component exports no {name} in {interface}")
        return self.instance.get_func(self.store, index)

    def version(self):
        return self.function("common", "get-version")(self.store)


class Instance:
    """One FMU instance of the component: `call(method, *args)` calls the draft's method of the
    instance resource of `kind` ("co-simulation" or "model-exchange"), and turns a returned
    error status into an exception that quotes the FMU's last log message."""

    def __init__(self, component, kind, *instantiate_args):
        self.component, self.kind = component, kind
        static = self.function(f"[static]{kind}-instance.instantiate-{kind}")
        self.handle = static(component.store, *instantiate_args)
        if self.handle is None:
            raise RuntimeError(f"instantiate-{kind} refused: {component.log[-1:]}")

    def function(self, name):
        return self.component.function(self.kind, name)

    def call(self, method, *args):
        result = self.function(f"[method]{self.kind}-instance.{method}")(
            self.component.store, self.handle, *args)
        if isinstance(result, str) and result not in ("ok", "warning"):
            raise RuntimeError(f"{method}: {result}: {self.component.log[-1:]}")
        return result


class Outputs:
    """The FMU's Float64 outputs from its FMI 3.0 model description: their names (an array
    variable's elements as name[k]), value references and how many values each holds."""

    def __init__(self, md):
        self.names, self.vrs, self.counts = [], [], []
        for v in md.modelVariables:
            if v.causality != "output" or v.type != "Float64":
                continue
            n = int(np.prod([int(d.start) for d in v.dimensions])) if v.dimensions else 1
            self.vrs.append(v.valueReference)
            self.counts.append(n)
            self.names += [v.name] if n == 1 else [f"{v.name}[{k + 1}]" for k in range(n)]

    @property
    def size(self):
        return sum(self.counts)


def read_fmu(path):
    with zipfile.ZipFile(path) as z:
        wasm = z.read(COMPONENT)
        manifest = ET.fromstring(z.read(MANIFEST))
    return wasm, manifest


def run_component(component, md, outputs, stop, step, tolerance, switch_at=None):
    """The default experiment through the component's co-simulation interface; the outputs at
    every point, and the serialised state at `switch_at` if given."""
    token = md.instantiationToken
    cs = Instance(component, "co-simulation", "wasm", token, "", False, False, False, False, [])
    cs.call("enter-initialization-mode", tolerance, 0.0, stop)
    cs.call("exit-initialization-mode")
    rows, saved = [cs.call("get-float64", outputs.vrs)], None
    n = int(round(stop / step))
    for k in range(n):
        cs.call("do-step", k * step, step, True)
        rows.append(cs.call("get-float64", outputs.vrs))
        if switch_at is not None and k + 1 == switch_at:
            saved = bytes(cs.call("get-fmu-state"))
    cs.call("terminate")
    return np.array(rows), saved


def native_slave(unzipped, md):
    slave = FMU3Slave(guid=md.instantiationToken, unzipDirectory=unzipped,
                      modelIdentifier=md.coSimulation.modelIdentifier, instanceName="native")
    slave.instantiate()
    return slave


def run_native(unzipped, md, outputs, stop, step, tolerance, start_state=None, first=0):
    """The same calls on the native FMI 3.0 library; from point `first` on a restored state."""
    slave = native_slave(unzipped, md)
    slave.enterInitializationMode(tolerance=tolerance, startTime=0.0, stopTime=stop)
    slave.exitInitializationMode()
    if start_state is not None:
        state = slave.deserializeFMUState(start_state)
        slave.setFMUState(state)
        slave.freeFMUState(state)
    rows = [slave.getFloat64(outputs.vrs, outputs.size)]
    for k in range(first, int(round(stop / step))):
        slave.doStep(k * step, step, True)
        rows.append(slave.getFloat64(outputs.vrs, outputs.size))
    slave.terminate()
    slave.freeInstance()
    return np.array(rows)


def agreement(a, b):
    """Largest |a - b| over each column's range (range 0: over 1), and the share of equal doubles."""
    span = np.ptp(b, axis=0)
    span[span == 0] = 1.0
    return float(np.max(np.abs(a - b) / span)), int(np.sum(a == b)), a.size


def model_exchange(component, unzipped, md):
    """States, nominals and derivatives at the start, and derivatives at perturbed states, from
    the component's model-exchange interface and from the native library; returns the largest
    relative difference and whether all were the same doubles."""
    token = md.instantiationToken
    me = Instance(component, "model-exchange", "wasm-me", token, "", False, False)
    native = FMU3Model(guid=token, unzipDirectory=unzipped,
                       modelIdentifier=md.modelExchange.modelIdentifier, instanceName="native-me")
    native.instantiate()
    n = me.call("get-number-of-continuous-states")
    for fmu in ("wasm", "native"):
        if fmu == "wasm":
            me.call("enter-initialization-mode", None, 0.0, None)
            me.call("exit-initialization-mode")
            me.call("enter-continuous-time-mode")
        else:
            native.enterInitializationMode(startTime=0.0)
            native.exitInitializationMode()
            native.enterContinuousTimeMode()
    x_w = np.array(me.call("get-continuous-states"))
    def native_array(get):
        values = np.zeros(n)
        get(values.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), n)
        return values

    x_n = native_array(native.getContinuousStates)
    nom_w = np.array(me.call("get-nominals-of-continuous-states"))
    nom_n = native_array(native.getNominalsOfContinuousStates)
    dx_w = [np.array(me.call("get-continuous-state-derivatives"))]
    dx_n = [native_array(native.getContinuousStateDerivatives)]
    rng = np.random.default_rng(1)
    for _ in range(3):
        x = x_n + 0.01 * nom_n * rng.standard_normal(n)
        me.call("set-continuous-states", list(x))
        native.setContinuousStates(x.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), n)
        dx_w.append(np.array(me.call("get-continuous-state-derivatives")))
        dx_n.append(native_array(native.getContinuousStateDerivatives))
    native.terminate()
    native.freeInstance()
    me.call("terminate")
    pairs = [(x_w, x_n), (nom_w, nom_n)] + list(zip(dx_w, dx_n))
    worst = max(float(np.max(np.abs(a - b) / np.maximum(np.abs(b), 1e-300))) for a, b in pairs)
    same = all(np.array_equal(a, b) for a, b in pairs)
    return n, worst, same


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--fmu3", default=str(FMU3))
    args = parser.parse_args(argv)
    wasm, manifest = read_fmu(args.fmu3)
    md = read_model_description(args.fmu3)
    de = md.defaultExperiment
    stop, step, tolerance = float(de.stopTime), float(de.stepSize), float(de.tolerance)
    outputs = Outputs(md)
    unzipped = extract(args.fmu3)
    try:
        ns = "{http://fmi-standard.org/fmi-ls-manifest}"
        print(f"component: {COMPONENT}; manifest {MANIFEST}: "
              f"{manifest.get(ns + 'fmi-ls-name')} {manifest.get(ns + 'fmi-ls-version')}")
        start = time.perf_counter()
        component = Component(wasm)
        load = time.perf_counter() - start
        print(f"Wasmtime compiled and instantiated it in {load:.2f} s (wall-clock)")
        print(f"get-version: {component.version()}")
        n = int(round(stop / step))
        half = n // 2
        start = time.perf_counter()
        wasm_rows, saved = run_component(component, md, outputs, stop, step, tolerance, half)
        t_wasm = time.perf_counter() - start
        start = time.perf_counter()
        native_rows = run_native(unzipped, md, outputs, stop, step, tolerance)
        t_native = time.perf_counter() - start
        worst, equal, total = agreement(wasm_rows, native_rows)
        print(f"Co-Simulation, the default experiment ({stop:g} s at {step:g} s points, "
              f"tolerance {tolerance:g}), {len(outputs.names)} outputs at {n + 1} points:")
        print(f"  largest |component - native| / range: {worst:.1e}; "
              f"the same doubles: {equal} of {total}")
        resumed = run_native(unzipped, md, outputs, stop, step, tolerance, saved, half)
        worst_r, equal_r, total_r = agreement(resumed[1:], native_rows[half + 1:])
        print(f"  the component's state at t = {half * step:g} s restored into the native "
              f"library and run to {stop:g} s: largest difference {worst_r:.1e}; the same "
              f"doubles: {equal_r} of {total_r}")
        n_states, worst_me, same_me = model_exchange(component, unzipped, md)
        print(f"Model Exchange at the start, {n_states} states: states, nominals and derivatives "
              f"(and the derivatives at 3 perturbed states) largest relative difference "
              f"{worst_me:.1e}; all the same doubles: {'yes' if same_me else 'no'}")
        print(f"cost of one run (wall-clock, one run each, an indication): component {t_wasm:.2f} s, "
              f"native {t_native:.2f} s")
        return {"worst": worst, "equal": equal, "total": total, "worst_resumed": worst_r,
                "equal_resumed": equal_r, "total_resumed": total_r, "worst_me": worst_me,
                "same_me": same_me, "version": component.version(),
                "manifest": {k.replace(ns, ""): v for k, v in manifest.attrib.items()}}
    finally:
        shutil.rmtree(unzipped, ignore_errors=True)


if __name__ == "__main__":
    main()
