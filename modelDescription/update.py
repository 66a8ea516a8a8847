#!/usr/bin/env python3
"""Rewrites the derived parts of modelDescription.xml after its variables were edited: the
continuous states and their derivatives (the last variables, from model_structure.json),
<ModelStructure> (Outputs, Derivatives and InitialUnknowns, by 1-based position, with their
dependencies) and the GUID (a hash of the file with the GUID left out). build.rs stays the judge:
it fails the build if any is stale. Usage: python3 modelDescription/update.py [--structure]
(needs rustc). With --structure it also rewrites model_structure.json from the compiled model
(the states and the dependencies, through tests/model_structure.rs, with cargo) and then the XML
again: the one command after adding an output or a state, or changing which states a
configuration has.

One source per rule: the XML is read through reader.py (ElementTree), the reader fmi3.py uses too;
regular expressions here only rewrite text (the state block, <ModelStructure>, the guid value), so
that the hand-written rest of the file keeps its layout and comments, which an ElementTree
round trip would lose. The GUID rule (FNV-1a) is written once, in src/fnv1a.rs: this script blanks
the guid, compiles tools/guid.rs (which includes src/fnv1a.rs) with plain rustc and lets it hash
the text. Not with cargo: the crate's build.rs refuses a stale GUID, so the crate cannot build
until this script has written the new one.

Continuous states (Model Exchange): FMI 2.0 fixes their number in the XML, while the model's
states depend on its structural parameters. model_structure.json, written by
tests/model_structure.rs from the compiled model, lists the union of the states of every
configuration with at most `plate_modes` plate modes, and the structural dependencies of each
derivative (on states and inputs) and of each output (on states). A state a configuration does not
have keeps its value with derivative 0. Each state carries the nominal value
model_structure.json gives it: what fmi2GetNominalsOfContinuousStates returns with the default
parameters (1 for a state the default configuration does not have).

Dependencies: an output depends directly on an input only where FEEDTHROUGH says so: the plate's
accelerations on the shaker forces (Newton's law: a force changes the acceleration at once), and
the LOES valve flow and the drive voltage controller.e_out on the reference r and on the external
drive e_in (the analog controller and the amplifier are static), and the loop's reference
controller.reference on r (r plus the command generator's move). Every other output is a
function of the state alone, y_pot and theta among them, so feeding y_pot back to r makes no
algebraic loop. tests/model_description.rs checks this table against the compiled model in every
configuration. Initially the outputs depend on the parameters and the same inputs (the simulation
starts from the rest state); the calculated plate frequencies plate.f[k] on the plate.*
parameters and hub.I_H."""

import json
import pathlib
import re
import subprocess
import tempfile

import reader

XML = pathlib.Path(__file__).with_name("modelDescription.xml")
STRUCTURE = pathlib.Path(__file__).with_name("model_structure.json")
GUID_TOOL = pathlib.Path(__file__).parent.parent / "tools" / "guid.rs"
STATES_MARK = "    <!-- continuous states and their derivatives: written by update.py from model_structure.json -->\n"
# Value references of the states and their derivatives: STATE_VR + k, DERIVATIVE_VR + k, k from 1.
STATE_VR, DERIVATIVE_VR = 10000, 20000


def state_description(name, plate_modes):
    element, _, variable = name.rpartition(".")
    kinds = {"p": "momentum p", "q": "displacement q"}
    entry = re.search(r"\[(\d+)\]$", variable)
    kind = kinds.get(re.sub(r"\[\d+\]$", "", variable))
    if entry and kind:
        kind = f"{kind}, entry {entry.group(1)},"
    what = f"{kind} of the bond-graph element {element}" if kind else f"{name} (integrated signal)"
    return (
        f"Continuous state (Model Exchange): {what}; stays at its value with derivative 0 in "
        f"configurations without it (Model Exchange declares the states of every configuration with up "
        f"to {plate_modes} plate modes)"
    )


def state_variables(structure):
    lines = [STATES_MARK]
    for k, state in enumerate(structure["states"], start=1):
        description = state_description(state, structure["plate_modes"])
        lines.append(
            f'    <ScalarVariable name="x.{state}" valueReference="{STATE_VR + k}" variability="continuous" initial="calculated"\n'
            f'      description="{description}">\n'
            f"      <Real{unit(structure, state, 0)}{nominal(structure, state)}/>\n"
            f"    </ScalarVariable>\n"
        )
    return lines


def nominal(structure, state):
    """The state's nominal attribute, its value the shortest text that reads back as the same
    double; none while model_structure.json has no nominal for it (tests/state_nominals.rs fails
    then)."""
    value = structure.get("nominals", {}).get(state)
    return "" if value is None else f' nominal="{float(value)!r}"'


def unit(structure, state, which):
    """The unit attribute of the state (which = 0) or of its derivative (which = 1), as the
    fragment that owns the state stated it (bond_graph::units); none while model_structure.json
    has no units for it."""
    units = structure.get("units", {}).get(state)
    return "" if units is None else f' unit="{units[which]}"'


def derivative_variables(structure, position):
    lines = []
    for k, state in enumerate(structure["states"], start=1):
        lines.append(
            f'    <ScalarVariable name="der(x.{state})" valueReference="{DERIVATIVE_VR + k}" variability="continuous" initial="calculated"\n'
            f'      description="Time derivative of x.{state}">\n'
            f'      <Real derivative="{position[f"x.{state}"]}"{unit(structure, state, 1)}/>\n'
            f"    </ScalarVariable>\n"
        )
    return lines

# Output name pattern -> the inputs it depends on directly.
FEEDTHROUGH = {
    r"acc\[\d+\]|acc_tip": ["F1", "F2"],
    r"q_valve|controller\.e_out": ["r", "e_in"],
    r"controller\.reference": ["r"],
}


def guid_for(text: str) -> str:
    """The GUID of `text`, whose guid attribute is blank, by the rule of src/fnv1a.rs (tools/guid.rs)."""
    with tempfile.TemporaryDirectory() as tmp:
        exe = pathlib.Path(tmp) / "guid"
        subprocess.run(["rustc", "--edition", "2021", "-o", str(exe), str(GUID_TOOL)], check=True)
        out = subprocess.run([str(exe)], input=text.encode(), stdout=subprocess.PIPE, check=True)
    return out.stdout.decode().strip()


def write_states(text, structure):
    """Replaces the generated state and derivative variables at the end of ModelVariables."""
    if STATES_MARK in text:
        text = text[: text.index(STATES_MARK)] + text[text.index("  </ModelVariables>") :]
    before = len(reader.variables(reader.parse(text)))
    position = {f"x.{s}": before + k for k, s in enumerate(structure["states"], start=1)}
    block = "".join(state_variables(structure) + derivative_variables(structure, position))
    at = text.index("  </ModelVariables>")
    return text[:at] + block + text[at:]


def main():
    structure = json.loads(STRUCTURE.read_text())
    text = write_states(XML.read_text(), structure)
    variables = reader.variables(reader.parse(text))
    names = [v.name for v in variables]
    position = {name: i for i, name in enumerate(names, start=1)}

    def feedthrough(name):
        return sorted(position[u] for pattern, inputs in FEEDTHROUGH.items() if re.fullmatch(pattern, name) for u in inputs)

    def known(name):
        return position[name] if name in position and name in inputs else position[f"x.{name}"]

    inputs = {v.name for v in variables if v.causality == "input"}

    def on_states(name):
        return [known(s) for s in structure["outputs"].get(name, [])]

    outputs, initial, parameters, plate = [], [], [], []
    for v in variables:
        i, name, causality = v.index, v.name, v.causality
        if causality == "output":
            outputs.append((i, sorted(feedthrough(name) + on_states(name))))
        if (causality == "output" and v.initial != "exact") or causality == "calculatedParameter":
            initial.append((i, name))
        if causality == "parameter":
            parameters.append(i)
            if name.startswith("plate.") or name == "hub.I_H":
                plate.append(i)
    initial = [(i, plate if name.startswith("plate.f[") else sorted(parameters + feedthrough(name))) for i, name in initial]
    # The states start at rest, a function of the parameters; the derivatives there depend on the
    # inputs as well.
    derivatives = []
    for state in structure["states"]:
        deps = sorted(known(d) for d in structure["derivatives"][state])
        derivatives.append((position[f"der(x.{state})"], deps))
        on_inputs = [d for d in deps if names[d - 1] in inputs]
        initial.append((position[f"x.{state}"], parameters))
        initial.append((position[f"der(x.{state})"], sorted(parameters + on_inputs)))
    initial.sort()

    def block(tag, unknowns):
        lines = "".join(
            f'      <Unknown index="{i}" dependencies="{" ".join(map(str, deps))}"/>\n' for i, deps in unknowns
        )
        return f"    <{tag}>\n{lines}    </{tag}>\n" if unknowns else ""

    model_structure = (
        "  <ModelStructure>\n"
        + block("Outputs", outputs)
        + block("Derivatives", derivatives)
        + block("InitialUnknowns", initial)
        + "  </ModelStructure>"
    )
    text = re.sub(r"  <ModelStructure>.*?</ModelStructure>", lambda _: model_structure, text, flags=re.S)
    text = re.sub(r'guid="[^"]*"', 'guid=""', text, count=1)
    guid = guid_for(text)
    text = text.replace('guid=""', f'guid="{guid}"', 1)
    XML.write_text(text)
    print(f"{XML}: {len(variables)} variables, {len(outputs)} outputs, {len(derivatives)} continuous states, guid {guid}")
    # The FMI 3.0 description is derived from this one.
    import fmi3

    fmi3.main()


def write_structure():
    """Rewrites model_structure.json from the compiled model (tests/model_structure.rs). The XML
    must be current first: the crate's build refuses a stale GUID."""
    import os

    root = pathlib.Path(__file__).resolve().parent.parent
    env = {**os.environ, "HSP_WRITE_MODEL_STRUCTURE": "1"}
    subprocess.run(["cargo", "test", "--release", "--quiet", "--test", "model_structure"], cwd=root, env=env, check=True)


if __name__ == "__main__":
    import sys

    main()
    if "--structure" in sys.argv[1:]:
        write_structure()
        main()
