#!/usr/bin/env python3
"""Writes modelDescription/fmi3/modelDescription.xml, the FMI 3.0 description, from
modelDescription/modelDescription.xml, the one source of truth for the FMU's variables. Nothing in
the FMI 3.0 file is written by hand: run this after every edit of the FMI 2.0 file (update.py runs
it at its end). Usage: python3 modelDescription/fmi3.py [--check]

With --check it writes nothing and exits 1 if the FMI 3.0 file is not what it would write (the test
suite runs this, so the two files cannot drift).

What changes from FMI 2.0 to 3.0:
- Scalar families named `base[1]`, ..., `base[n]` with consecutive value references and the same
  type, causality, variability and unit (continuous states and their derivatives excepted) become
  one array variable `base` with `<Dimension
  start="n"/>` and the value reference of `base[1]` (the accelerometers `acc`, the plate
  frequencies `plate.f`). The FMI 3.0 layer (src/fmi3/variables.rs) groups the same way, and the
  test suite checks that it finds exactly these arrays.
- Real becomes Float64, Integer Int32 (a switch, named by an <Enumeration variable=...> of the
  project's vendor annotation, becomes an Enumeration of that type), an Enumeration stays one (with its declaredType; the
  importer reaches it through fmi3GetInt64/fmi3SetInt64), and each <SimpleType> with an
  <Enumeration> of <TypeDefinitions> becomes an <EnumerationType> with the same items; an `independent` variable `time` is added with value
  reference 0 (FMI 3.0 requires one; 0 is free in the FMI 2.0 table).
- The vendor annotation's <Positive> and <Magnitudes> rules become the text of an <Annotation
  type="hydraulic-slewing-plate"> after <ModelStructure>: `positive = <names>` and
  `magnitudes = <smallest> <largest>`, a line each.
- `<ModelStructure>` refers to value references, not indices: Output, ContinuousStateDerivative
  and InitialUnknown elements, with the dependencies of an array the union over its elements.
- The instantiation token is the FMI 2.0 GUID: both are a hash of the same source.
"""

import pathlib
import re
import sys

import reader

HERE = pathlib.Path(__file__).parent
FMI2 = HERE / "modelDescription.xml"
FMI3 = HERE / "fmi3" / "modelDescription.xml"

TYPES = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean", "String": "String", "Enumeration": "Enumeration"}
TIME_VR = 0

# An array's description: its elements describe themselves one by one in FMI 2.0.
ARRAY_DESCRIPTIONS = {
    "acc": "The 12 accelerometers of the 4 x 3 grid on the plate, row by row from the hub (x = 1a/4, 2a/4, 3a/4, a at y = 1b/6, 3b/6, 5b/6 for elements 1-3, 4-6, 7-9, 10-12): absolute normal acceleration, rigid rotation included",
    "plate.f": "Natural frequencies of the plate model in ascending order (eq. 14; chosen formulation and root condition, hub free, rigid mode left out; 0 beyond the model's mode count)",
}


def esc(s):
    return s.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;").replace('"', "&quot;")


def attrs(pairs):
    return "".join(f' {k}="{esc(str(v))}"' for k, v in pairs if v is not None)


class Var(reader.Variable):
    """A variable of the FMI 2.0 file (read by reader.py) with what FMI 3.0 makes of it."""

    @property
    def type(self):
        return TYPES[self.kind]

    def family(self):
        m = re.fullmatch(r"(.*)\[(\d+)\]", self.name)
        return (m.group(1), int(m.group(2))) if m else (None, None)

    def signature(self):
        a = {k: v for k, v in self.type_attrs.items() if k != "start"}
        return (self.type, self.causality, self.variability, self.initial, tuple(sorted(a.items())))


def group(variables):
    """Scalar families base[1..n] with consecutive value references and one signature -> arrays.
    Continuous states and their derivatives stay scalars (an array state would need an array
    derivative of the same shape, and `der(x[k])` is not a family). Returns a list of
    (name, [Var...]) in table order; a scalar is a list of one."""
    state_related = {v.index for v in variables if "derivative" in v.type_attrs}
    state_related |= {int(v.type_attrs["derivative"]) for v in variables if "derivative" in v.type_attrs}
    out, i = [], 0
    while i < len(variables):
        v = variables[i]
        base, k = v.family()
        members = [v]
        if base is not None and k == 1 and v.index not in state_related:
            j = i + 1
            while j < len(variables):
                w = variables[j]
                wb, wk = w.family()
                if (wb == base and wk == len(members) + 1 and w.vr == v.vr + len(members)
                        and w.signature() == v.signature() and w.index not in state_related):
                    members.append(w)
                    j += 1
                else:
                    break
        if len(members) > 1:
            out.append((base, members))
        else:
            out.append((v.name, [v]))
        i += len(members)
    return out


def generate(text):
    root = reader.parse(text)
    variables = reader.variables(root, Var)
    # The switches: an Integer in FMI 2.0 (libcosim and ecos skip FMI 2.0 Enumerations), an
    # Enumeration of the type the project's vendor annotation names in FMI 3.0.
    switches = {e.get("variable"): e.get("declaredType")
                for e in root.findall("VendorAnnotations/Tool[@name='hydraulic-slewing-plate']//Enumeration")}
    for v in variables:
        if v.name in switches:
            v.kind = "Enumeration"
            v.type_attrs = {"declaredType": switches.pop(v.name), "start": v.type_attrs["start"]}
    if switches:
        raise SystemExit(f"switches that are no variable: {sorted(switches)}")
    if any(v.vr == TIME_VR for v in variables):
        raise SystemExit(f"value reference {TIME_VR} is taken; the FMI 3.0 time variable needs it")
    groups = group(variables)
    # FMI 2.0 index -> FMI 3.0 value reference (an element maps to its array).
    vr_of_index = {}
    for _, members in groups:
        for m in members:
            vr_of_index[m.index] = members[0].vr

    out = ['<?xml version="1.0" encoding="UTF-8"?>']
    out.append("<!-- Written by modelDescription/fmi3.py from modelDescription/modelDescription.xml: do not edit. -->")
    keep = ["modelName", "description", "author", "version", "copyright", "license", "generationTool", "variableNamingConvention"]
    head = [("fmiVersion", "3.0")] + [(k, root.get(k)) for k in keep[:2]] + [("instantiationToken", root.get("guid"))] + [(k, root.get(k)) for k in keep[2:]]
    out.append("<fmiModelDescription" + "".join(f'\n  {k}="{esc(v)}"' for k, v in head if v is not None) + ">")
    out.append("")

    me, cs = root.find("ModelExchange"), root.find("CoSimulation")
    def common(element):
        # The FMU-state capabilities as the FMI 2.0 element declares them; the adjoint comes from
        # the same exact Jacobian as the directional derivative.
        dd = element.get("providesDirectionalDerivative", "false")
        return [
            ("canGetAndSetFMUState", element.get("canGetAndSetFMUstate", "false")),
            ("canSerializeFMUState", element.get("canSerializeFMUstate", "false")),
            ("providesDirectionalDerivatives", dd),
            ("providesAdjointDerivatives", dd),
        ]

    if me is not None:
        out.append("  <ModelExchange" + attrs([("modelIdentifier", me.get("modelIdentifier")), ("needsCompletedIntegratorStep", "false")] + common(me)) + "/>")
        out.append("")
    if cs is not None:
        out.append(
            "  <CoSimulation"
            + attrs(
                [
                    ("modelIdentifier", cs.get("modelIdentifier")),
                    ("canHandleVariableCommunicationStepSize", cs.get("canHandleVariableCommunicationStepSize")),
                    ("canBeInstantiatedOnlyOncePerProcess", "false"),
                ]
                + common(cs)
                + [("hasEventMode", "false"), ("providesIntermediateUpdate", "false"), ("canReturnEarlyAfterIntermediateUpdate", "false")]
            )
            + "/>"
        )
        out.append("")

    units = root.find("UnitDefinitions")
    if units is not None:
        out.append("  <UnitDefinitions>")
        for u in units:
            inner = "".join(f"<{c.tag}{attrs(c.attrib.items())}/>" for c in u)
            out.append(f'    <Unit name="{esc(u.get("name"))}">{inner}</Unit>' if inner else f'    <Unit name="{esc(u.get("name"))}"/>')
        out.append("  </UnitDefinitions>")
        out.append("")
    types = root.find("TypeDefinitions")
    if types is not None:
        out.append("  <TypeDefinitions>")
        for t in types.findall("SimpleType"):
            e = t.find("Enumeration")
            if e is None:
                raise SystemExit(f"type {t.get('name')}: only Enumeration types are translated")
            out.append(f"    <EnumerationType{attrs([('name', t.get('name')), ('description', t.get('description'))] + list(e.attrib.items()))}>")
            for item in e.findall("Item"):
                out.append(f"      <Item{attrs(item.attrib.items())}/>")
            out.append("    </EnumerationType>")
        out.append("  </TypeDefinitions>")
        out.append("")
    cats = root.find("LogCategories")
    if cats is not None:
        out.append("  <LogCategories>")
        for c in cats:
            out.append(f"    <Category{attrs(c.attrib.items())}/>")
        out.append("  </LogCategories>")
        out.append("")
    de = root.find("DefaultExperiment")
    if de is not None:
        out.append(f"  <DefaultExperiment{attrs(de.attrib.items())}/>")
        out.append("")

    out.append("  <ModelVariables>")
    out.append(f'    <Float64 name="time" valueReference="{TIME_VR}" causality="independent" variability="continuous" description="Simulation time" unit="s"/>')
    for name, members in groups:
        v = members[0]
        is_array = len(members) > 1
        description = ARRAY_DESCRIPTIONS.get(name, v.description) if is_array else v.description
        a = [
            ("name", name),
            ("valueReference", v.vr),
            ("description", description),
            ("causality", v.causality),
            ("variability", v.variability),
            ("initial", v.initial),
        ]
        ta = v.type_attrs
        for key in ("declaredType", "quantity", "unit", "displayUnit", "relativeQuantity", "min", "max", "nominal", "unbounded"):
            if key in ta:
                a.append((key, ta[key]))
        starts = [m.type_attrs.get("start") for m in members]
        if v.type == "String":
            raise SystemExit("String variables: write their <Start> children when the model has any")
        if all(s is not None for s in starts):
            a.append(("start", " ".join(starts)))
        elif any(s is not None for s in starts):
            raise SystemExit(f"{name}: some elements have a start value and some not")
        if "derivative" in ta:
            a.append(("derivative", vr_of_index[int(ta["derivative"])]))
        if is_array:
            out.append(f"    <{v.type}{attrs(a)}>")
            out.append(f'      <Dimension start="{len(members)}"/>')
            out.append(f"    </{v.type}>")
        else:
            out.append(f"    <{v.type}{attrs(a)}/>")
    out.append("  </ModelVariables>")
    out.append("")

    structure = root.find("ModelStructure")
    out.append("  <ModelStructure>")
    for tag2, tag3 in (("Outputs", "Output"), ("Derivatives", "ContinuousStateDerivative"), ("InitialUnknowns", "InitialUnknown")):
        block = structure.find(tag2) if structure is not None else None
        if block is None:
            continue
        merged = {}  # FMI 3.0 value reference -> dependencies (None: on everything)
        for u in block:
            vr = vr_of_index[int(u.get("index"))]
            deps = u.get("dependencies")
            if deps is None:
                merged[vr] = None
            elif merged.get(vr, set()) is not None:
                merged.setdefault(vr, set()).update(vr_of_index[int(d)] for d in deps.split())
        for vr in sorted(merged, key=lambda r: min(m.index for _, ms in groups if ms[0].vr == r for m in ms)):
            deps = merged[vr]
            dep = "" if deps is None else f' dependencies="{" ".join(map(str, sorted(deps)))}"'
            out.append(f'    <{tag3} valueReference="{vr}"{dep}/>')
    out.append("  </ModelStructure>")
    # The rules min and max cannot express (strictly positive parameters, the magnitudes a
    # parameter may have), as the FMI 2.0 file's vendor annotation states them, one `name =
    # values` line each: an FMI 3.0 <Annotation> may hold elements, but importers that read it
    # as text only (the Rust fmi crate 0.8) refuse a file whose annotation has any. The
    # switches need no rule here: they are Enumerations.
    rules = root.find("VendorAnnotations/Tool[@name='hydraulic-slewing-plate']/Rules")
    if rules is None:
        raise SystemExit("the FMI 2.0 file has no <Rules> in its vendor annotation")
    lines = []
    for rule in rules:
        if rule.tag == "Positive":
            lines.append("positive = " + " ".join(rule.get("names").split()))
        elif rule.tag == "Magnitudes":
            lines.append(f"magnitudes = {rule.get('smallest')} {rule.get('largest')}")
    out.append("")
    out.append("  <Annotations>")
    out.append('    <Annotation type="hydraulic-slewing-plate">')
    out.extend(f"{esc(line)}" for line in lines)
    out.append("    </Annotation>")
    out.append("  </Annotations>")
    out.append("</fmiModelDescription>")
    return "\n".join(out) + "\n"


def main():
    text = generate(FMI2.read_text())
    if "--check" in sys.argv[1:]:
        if not FMI3.exists() or FMI3.read_text() != text:
            print(f"{FMI3} is stale: run python3 modelDescription/fmi3.py", file=sys.stderr)
            sys.exit(1)
        return
    FMI3.parent.mkdir(exist_ok=True)
    FMI3.write_text(text)
    n = text.count("valueReference=") - text.count("<Output ") - text.count("<InitialUnknown ") - text.count("<ContinuousStateDerivative ")
    print(f"{FMI3}: {n} variables")


if __name__ == "__main__":
    main()
