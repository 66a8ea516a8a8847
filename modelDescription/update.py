#!/usr/bin/env python3
"""Rewrites the derived parts of modelDescription.xml after its variables were edited:
<ModelStructure> (Outputs and InitialUnknowns, by 1-based position) and the GUID (a hash of the
file with the GUID left out, as build.rs computes it). build.rs stays the judge: it fails the
build if either is stale. Usage: python3 modelDescription/update.py"""

import pathlib
import re

XML = pathlib.Path(__file__).with_name("modelDescription.xml")


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
    outputs, initial = [], []
    for i, attrs in enumerate(variables, start=1):
        causality = re.search(r'causality="(\w+)"', attrs)
        causality = causality.group(1) if causality else "local"
        init = re.search(r'initial="(\w+)"', attrs)
        if causality == "output":
            outputs.append(i)
        if (causality == "output" and not (init and init.group(1) == "exact")) or causality == "calculatedParameter":
            initial.append(i)

    def block(tag, indices):
        lines = "".join(f'      <Unknown index="{i}"/>\n' for i in indices)
        return f"    <{tag}>\n{lines}    </{tag}>\n" if indices else ""

    structure = "  <ModelStructure>\n" + block("Outputs", outputs) + block("InitialUnknowns", initial) + "  </ModelStructure>"
    text = re.sub(r"  <ModelStructure>.*?</ModelStructure>", lambda _: structure, text, flags=re.S)
    text = re.sub(r'guid="[^"]*"', 'guid=""', text, count=1)
    text = text.replace('guid=""', f'guid="{guid_for(text)}"', 1)
    XML.write_text(text)
    print(f"{XML}: {len(variables)} variables, {len(outputs)} outputs, guid {guid_for(text)}")


if __name__ == "__main__":
    main()
