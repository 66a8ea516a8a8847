"""The licences: the repository's, and what both FMUs carry in documentation/licenses/ (FMI 3.0's
folder for them, entry point license.txt): the project's licence, and the licence files of every
crate compiled into the binaries, none of the tool-only crates."""

import json
import re
import subprocess
import tomllib
import zipfile

import pytest

from conftest import ROOT

FMUS = [ROOT / "fmu" / "HydraulicSlewingPlate.fmu",
        ROOT / "fmu" / "fmi3" / "HydraulicSlewingPlate.fmu"]
# Crates only the command-line tools use (Cargo.toml's `cli` feature): never in the FMU.
TOOL_ONLY = ["clap", "zip", "plotters", "dejavu", "roxmltree"]


def library_crates():
    """The library's run-time crates, found another way than `hsp package` does: cargo metadata's
    resolved graph from the package, along normal dependencies of the features the FMU's build
    enables (none), skipping procedural macros."""
    meta = json.loads(subprocess.run(
        ["cargo", "metadata", "--format-version", "1", "--no-default-features"],
        cwd=ROOT, capture_output=True, text=True, check=True).stdout)
    packages = {p["id"]: p for p in meta["packages"]}
    nodes = {n["id"]: n for n in meta["resolve"]["nodes"]}
    root = meta["resolve"]["root"]
    # Optional dependencies enter only through features; with no features none is enabled.
    optional = {d["name"] for d in packages[root]["dependencies"] if d.get("optional")}
    found, stack = set(), [root]
    while stack:
        pid = stack.pop()
        p = packages[pid]
        if pid in found or any("proc-macro" in t["kind"] for t in p["targets"]):
            continue
        found.add(pid)
        for dep in nodes[pid]["deps"]:
            normal = any(k["kind"] is None for k in dep["dep_kinds"])
            if normal and not (pid == root and packages[dep["pkg"]]["name"] in optional):
                stack.append(dep["pkg"])
    found.discard(root)
    return {(packages[p]["name"], packages[p]["version"]) for p in found}


def test_the_repository_has_its_licence():
    cargo = tomllib.loads((ROOT / "Cargo.toml").read_text())
    assert cargo["package"]["license"] == "MIT OR Apache-2.0"
    assert "Permission is hereby granted" in (ROOT / "LICENSE-MIT").read_text()
    assert "Apache License" in (ROOT / "LICENSE-APACHE").read_text()
    assert "MIT OR Apache-2.0" in (ROOT / "LICENSE").read_text()


@pytest.mark.parametrize("fmu", FMUS, ids=["fmi2", "fmi3"])
def test_each_fmu_carries_the_licences_of_everything_compiled_into_it(fmu_path, fmu):
    with zipfile.ZipFile(fmu) as z:
        names = z.namelist()
        text = z.read("documentation/licenses/license.txt").decode()
        for own in ("LICENSE-MIT", "LICENSE-APACHE"):
            assert z.read(f"documentation/licenses/{own}") == (ROOT / own).read_bytes()
        listed = set(re.findall(r"^  (\S+)\s+(\d\S*)\s+\S", text, re.M))
        # Every crate the graph holds is listed, with at least one licence file of its own.
        metadata = library_crates()
        assert {"nalgebra", "libm", "serde_json"} <= {name for name, _ in listed}
        # cargo metadata resolves optional features of dependencies more widely than a build
        # does (it unifies across dev-dependencies), so the FMU's list must be a subset of it.
        assert listed <= metadata, listed - metadata
        for name, version in listed:
            files = [n for n in names
                     if n.startswith(f"documentation/licenses/third-party/{name}-{version}/")]
            assert files, f"{name} {version}: no licence file"
            assert all(len(z.read(f)) > 10 for f in files)
        assert not {name for name, _ in listed} & set(TOOL_ONLY)
        windows = any(n.startswith("binaries/win64/") or n.startswith("binaries/x86_64-windows/")
                      for n in names)
        assert ("mingw-w64" in text) == windows
