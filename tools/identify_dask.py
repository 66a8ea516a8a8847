#!/usr/bin/env python3
"""The starts of ``hsp identify --starts N`` spread over Dask workers (dask.distributed).

A fit that is not convex is run from N starting points (docs/identify.md, "Many starts"). On one
machine ``hsp identify --starts N`` runs them on its threads. This tool runs each start as one
Dask task instead: the task runs ``hsp identify ARGS --starts N --seed S --start K``, which fits
from start K alone and prints where it ended as one JSON line (the doubles as their bits). The
lines are gathered here and ``hsp identify ARGS --starts N --seed S --ends FILE`` makes the fit,
its intervals, its minima and its report from them, as if the starts had run on its threads: the
output is the same, to the bit (tests/python/test_identify_dask.py).

The workers need no shared file system: the ``hsp`` binary and the data files the arguments name
(``--frf INPUT:OUTPUT:FILE``, ``--peaks INPUT:OUTPUT:FILE``, ``--series FILE``) are sent with the
tasks, and each worker writes them into its own directory. The workers must run the same
operating system and processor family as the ``hsp`` binary (Linux x86-64 for a build here).

Runs on a LocalCluster by default (``--workers N``), or on a running scheduler
(``--scheduler tcp://host:8786``). Everything after ``--`` goes to ``hsp identify``:

    python tools/identify_dask.py --starts 6 --seed 1 -- \\
        --frf r:acc_tip:measured/acc_tip.csv --fit plate.E:1e10:4e11 --json
"""

from __future__ import annotations

import argparse
import hashlib
import os
import pathlib
import subprocess
import sys
import tempfile

ROOT = pathlib.Path(__file__).resolve().parents[1]
DEFAULT_HSP = ROOT / "target" / "release" / "hsp"

#: The arguments of ``hsp identify`` that name a data file, and where in the value the file is.
DATA_FLAGS = {"--frf": 2, "--peaks": 2, "--series": 0}


def split_data(args: list[str]) -> tuple[list[str], dict[str, tuple[str, bytes]]]:
    """The arguments with every data file replaced by a placeholder ``{dataK}``, and by
    placeholder the file's name and contents."""
    out, files = [], {}
    i = 0
    while i < len(args):
        flag, value = args[i], None
        if "=" in flag and flag.split("=", 1)[0] in DATA_FLAGS:
            flag, value = flag.split("=", 1)
        elif flag in DATA_FLAGS and i + 1 < len(args):
            value = args[i + 1]
            i += 1
        if value is None:
            out.append(flag)
        else:
            parts = value.split(":", DATA_FLAGS[flag])
            key = f"{{data{len(files)}}}"
            path = pathlib.Path(parts[-1])
            files[key] = (path.name, path.read_bytes())
            parts[-1] = key
            out += [flag, ":".join(parts)]
        i += 1
    return out, files


def run_start(hsp: bytes, args: list[str], files: dict[str, tuple[str, bytes]], k: int) -> str:
    """On a worker: writes the binary (once per worker and content) and the data files, runs
    ``hsp identify ARGS --start K`` and returns its JSON line; raises with hsp's message."""
    base = pathlib.Path(tempfile.gettempdir()) / f"hsp-identify-dask-{os.getuid()}"
    base.mkdir(parents=True, exist_ok=True)
    binary = base / f"hsp-{hashlib.sha256(hsp).hexdigest()[:16]}"
    if not binary.exists():
        part = binary.with_suffix(f".{os.getpid()}")
        part.write_bytes(hsp)
        part.chmod(0o755)
        part.replace(binary)
    with tempfile.TemporaryDirectory(dir=base) as work:
        paths = {}
        for key, (name, data) in files.items():
            # In a folder of its own under its own name: hsp's messages name the user's file.
            path = pathlib.Path(work) / key.strip("{}") / name
            path.parent.mkdir()
            path.write_bytes(data)
            paths[key] = str(path)
        argv = []
        for a in args:
            for key, path in paths.items():
                a = a.replace(key, path)
            argv.append(a)
        done = subprocess.run([str(binary), "identify", *argv, "--start", str(k)],
                              capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"start {k}: {done.stderr.strip()}")
    return done.stdout.strip()


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    if "--" in argv:
        cut = argv.index("--")
        ours, theirs = argv[:cut], argv[cut + 1:]
    else:
        ours, theirs = argv, []
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--starts", type=int, required=True, help="the number of starts N (> 1)")
    p.add_argument("--seed", type=int, default=1, help="the seed of the drawn starts")
    p.add_argument("--hsp", default=str(DEFAULT_HSP),
                   help="the hsp binary (default: target/release/hsp)")
    p.add_argument("--scheduler", help="a running Dask scheduler; default: a LocalCluster")
    p.add_argument("--workers", type=int, default=os.cpu_count(),
                   help="LocalCluster workers (default: the number of CPUs)")
    a = p.parse_args(ours)
    if a.starts < 2:
        p.error("--starts N needs N > 1 (one start needs no cluster: run hsp identify)")
    for flag in ("--starts", "--seed", "--start", "--ends", "--jobs"):
        if any(t == flag or t.startswith(flag + "=") for t in theirs):
            p.error(f"{flag} is this tool's to give; leave it out of the arguments after --")
    hsp = pathlib.Path(a.hsp)
    if not hsp.is_file():
        p.error(f"{hsp}: no hsp binary (cargo build --release --bin hsp, or --hsp PATH)")
    common = ["--starts", str(a.starts), "--seed", str(a.seed)]
    # The arguments without --out and --report (the end's lines only), and the data's files.
    task_args, skip = [], False
    for t in theirs:
        if skip:
            skip = False
            continue
        if t in ("--out", "--report"):
            skip = True
            continue
        if t.split("=", 1)[0] in ("--out", "--report", "--json"):
            continue
        task_args.append(t)
    task_args, files = split_data(task_args)

    from distributed import Client, LocalCluster
    if a.scheduler:
        client, cluster = Client(a.scheduler), None
    else:
        cluster = LocalCluster(n_workers=a.workers, threads_per_worker=1, processes=True,
                               dashboard_address=None)
        client = Client(cluster)
    try:
        binary = client.scatter(hsp.read_bytes(), broadcast=True)
        futures = [client.submit(run_start, binary, task_args + common, files, k, pure=False)
                   for k in range(a.starts)]
        lines = client.gather(futures)
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    with tempfile.NamedTemporaryFile("w", suffix=".jsonl", delete=False) as f:
        f.write("\n".join(lines) + "\n")
        ends = f.name
    try:
        done = subprocess.run([str(hsp), "identify", *theirs, *common, "--ends", ends])
    finally:
        os.unlink(ends)
    return done.returncode


if __name__ == "__main__":
    sys.exit(main())
