#!/usr/bin/env python3
"""Rewrites the derived parts of modelDescription.xml after its variables were edited:
<ModelStructure> (Outputs and InitialUnknowns, by 1-based position, with their dependencies) and
the GUID (a hash of the file with the GUID left out, as build.rs computes it). build.rs stays the
judge: it fails the build if either is stale. Usage: python3 modelDescription/update.py

Dependencies: an output depends directly on an input only where FEEDTHROUGH says so: the plate's
accelerations on the shaker forces (Newton's law: a force changes the acceleration at once), and
the LOES valve flow and the drive voltage controller.e_out on the reference r and on the external
drive e_in (the analog controller and the amplifier are static). Every other output is a
function of the state alone, y_pot and theta among them, so feeding y_pot back to r makes no
algebraic loop. tests/model_description.rs checks this table against the compiled model in every
configuration. Initially the outputs depend on the parameters and the same inputs (the simulation
starts from the rest state); the calculated plate frequencies plate.f[k] on the plate.*
parameters and hub.I_H."""

import pathlib
import re

XML = pathlib.Path(__file__).with_name("modelDescription.xml")

# Output name pattern -> the inputs it depends on directly.
FEEDTHROUGH = {
    r"acc\[\d+\]|acc_tip": ["F1", "F2"],
    r"q_valve|controller\.e_out": ["r", "e_in"],
}


def fnv1a(data: bytes, basis: int) -> int:
    h = basis
    for b in data:
        h ^= b
        h = (h * 0x100000001B3) & 0xFFFFFFFFFFFFFFFF
    return h


def guid_for(text: str) -> str:
    current = re.search(r'guid="([^"]*)"', text).group(1)
    blanked = text.replace(f'guid="{current}"', 'guid=""', 1).encode()
    a = fnv1a(blanked, 0xCBF29CE484222325)
    b = fnv1a(blanked, 0x84222325CBF29CE4)
    return "{%08x-%04x-%04x-%04x-%012x}" % (a >> 32, (a >> 16) & 0xFFFF, a & 0xFFFF, b >> 48, b & 0xFFFFFFFFFFFF)


def main():
    text = XML.read_text()
    variables = re.findall(r"<ScalarVariable\b(.*?)>", text, flags=re.S)
    names = [re.search(r'name="([^"]*)"', attrs).group(1) for attrs in variables]
    position = {name: i for i, name in enumerate(names, start=1)}

    def feedthrough(name):
        return sorted(position[u] for pattern, inputs in FEEDTHROUGH.items() if re.fullmatch(pattern, name) for u in inputs)

    outputs, initial, parameters, plate = [], [], [], []
    for i, attrs in enumerate(variables, start=1):
        name = names[i - 1]
        causality = re.search(r'causality="(\w+)"', attrs)
        causality = causality.group(1) if causality else "local"
        init = re.search(r'initial="(\w+)"', attrs)
        if causality == "output":
            outputs.append((i, feedthrough(name)))
        if (causality == "output" and not (init and init.group(1) == "exact")) or causality == "calculatedParameter":
            initial.append((i, name))
        if causality == "parameter":
            parameters.append(i)
            if name.startswith("plate.") or name == "hub.I_H":
                plate.append(i)
    initial = [(i, plate if name.startswith("plate.f[") else sorted(parameters + feedthrough(name))) for i, name in initial]

    def block(tag, unknowns):
        lines = "".join(
            f'      <Unknown index="{i}" dependencies="{" ".join(map(str, deps))}"/>\n' for i, deps in unknowns
        )
        return f"    <{tag}>\n{lines}    </{tag}>\n" if unknowns else ""

    structure = "  <ModelStructure>\n" + block("Outputs", outputs) + block("InitialUnknowns", initial) + "  </ModelStructure>"
    text = re.sub(r"  <ModelStructure>.*?</ModelStructure>", lambda _: structure, text, flags=re.S)
    text = re.sub(r'guid="[^"]*"', 'guid=""', text, count=1)
    text = text.replace('guid=""', f'guid="{guid_for(text)}"', 1)
    XML.write_text(text)
    print(f"{XML}: {len(variables)} variables, {len(outputs)} outputs, guid {guid_for(text)}")
    # The FMI 3.0 description is derived from this one.
    import fmi3

    fmi3.main()


if __name__ == "__main__":
    main()
