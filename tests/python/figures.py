"""Checks that a figure file is a real, non-trivial picture: PNG signature and IHDR size, or an SVG
document with drawing elements."""

import struct
import xml.etree.ElementTree as ET

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def png_size(data: bytes):
    """(width, height) of a PNG, asserting its signature and IHDR chunk."""
    assert data[:8] == PNG_SIGNATURE, "not a PNG"
    length, kind = struct.unpack(">I4s", data[8:16])
    assert kind == b"IHDR" and length == 13, "PNG without IHDR"
    return struct.unpack(">II", data[16:24])


def assert_png(data: bytes, min_width=400, min_height=300, min_bytes=10_000):
    w, h = png_size(data)
    assert w >= min_width and h >= min_height, (w, h)
    # A blank or near-blank picture compresses to a few kB; a plot with text and curves does not.
    assert len(data) >= min_bytes, len(data)
    return w, h


def assert_svg(data: bytes, min_elements=20, min_texts=3):
    root = ET.fromstring(data)
    assert root.tag.endswith("svg"), root.tag
    drawn = [e for e in root.iter() if e.tag.split("}")[-1] in
             ("path", "line", "polyline", "polygon", "rect", "circle", "ellipse")]
    texts = [e for e in root.iter() if e.tag.split("}")[-1] == "text"]
    assert len(drawn) >= min_elements, len(drawn)
    assert len(texts) >= min_texts, len(texts)
    return root
