"""The Python reader of modelDescription/modelDescription.xml (FMI 2.0), shared by update.py and
fmi3.py: where a variable's facts sit in the XML and what an absent attribute means (FMI 2.0's
defaults) are written here once, with ElementTree. The Rust side has its own single reader,
tools/model_description.rs (build.rs and hsp); the two languages cannot share code, and build.rs
judges what both read (it fails the build on a stale or inconsistent file)."""

import xml.etree.ElementTree as ET


def parse(text):
    """The root element of a model description's text."""
    return ET.fromstring(text)


class Variable:
    """A <ScalarVariable> and its type element; `index` is its 1-based position."""

    def __init__(self, index, sv):
        self.index = index
        self.name = sv.get("name")
        self.vr = int(sv.get("valueReference"))
        self.causality = sv.get("causality", "local")
        self.variability = sv.get("variability", "continuous")
        self.initial = sv.get("initial")
        self.description = sv.get("description")
        typed = next(iter(sv))
        # Real, Integer, Boolean, String or Enumeration.
        self.kind = typed.tag
        self.type_attrs = dict(typed.attrib)


def variables(root, cls=Variable):
    """The scalar variables of <ModelVariables> in order, as `cls` (Variable or a subclass)."""
    return [cls(i, sv) for i, sv in enumerate(root.find("ModelVariables").findall("ScalarVariable"), start=1)]
