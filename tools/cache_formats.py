"""Size and load time of a run-cache entry format, on a real cache's runs (a one-off measurement
behind the choice of :mod:`magexp.cache`'s format; not part of ``make bench``).

    python tools/cache_formats.py OLD_CACHE [--limit N] [--rounds R]

``OLD_CACHE``: a run cache of the former format (``<key>.pkl`` pickles of ``RunOutput``; your own, it
is unpickled). Each run is written in three formats into a temporary folder: the former pickle, the
current entry (:func:`magexp.cache.pack`: JSON header + raw arrays, digest, key and type checked on
read) and an ``.npz`` (``numpy.savez``: a JSON member and one member per array, read with
``allow_pickle=False``, with the same digest check). It prints each format's total size and the wall and CPU
time to read every entry back (median of ``R`` rounds, formats alternating, files in the page cache), and
the share of the current format's time spent on its digest.
"""

from __future__ import annotations

import argparse
import dataclasses
import hashlib
import io
import json
import pickle
import shutil
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from magexp import cache


def npz_bytes(key: str, out) -> bytes:
    arrays: list = []
    tree = cache._tree({f.name: getattr(out, f.name) for f in dataclasses.fields(out)}, arrays, "run")
    head = json.dumps({"key": key, "kind": "RunOutput", "value": tree}).encode()
    h = hashlib.sha256(head)
    for a in arrays:
        h.update(a.tobytes())
    members = {f"a{i}": a for i, a in enumerate(arrays)}
    buf = io.BytesIO()
    np.savez(buf, head=np.frombuffer(head, np.uint8), digest=np.frombuffer(h.digest(), np.uint8), **members)
    return buf.getvalue()


def npz_load(path: Path, key: str):
    with np.load(path, allow_pickle=False) as z:
        head = z["head"].tobytes()
        arrays = [z[f"a{i}"] for i in range(len(z.files) - 2)]
        h = hashlib.sha256(head)
        for a in arrays:
            h.update(a.tobytes())
        if h.digest() != z["digest"].tobytes():
            raise cache.InvalidEntry("digest")
    meta = json.loads(head, object_hook=lambda d: arrays[d["$array"]] if "$array" in d else d)
    if meta["key"] != key:
        raise cache.InvalidEntry("key")
    return cache._run_output(meta["value"])


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("old_cache", type=Path)
    p.add_argument("--limit", type=int, default=None)
    p.add_argument("--rounds", type=int, default=5)
    args = p.parse_args()
    files = sorted(args.old_cache.rglob("*.pkl"))[:args.limit]
    tmp = Path(tempfile.mkdtemp(prefix="magexp-formats-"))
    keys, sizes = [], {"pickle": 0, "entry": 0, "npz": 0}
    for path in files:
        raw = path.read_bytes()
        out = pickle.loads(raw)
        key = path.stem
        keys.append(key)
        for name, data in (("pickle", raw), ("entry", cache.pack(key, "RunOutput", {
                f.name: getattr(out, f.name) for f in dataclasses.fields(out)})), ("npz", npz_bytes(key, out))):
            (tmp / name).mkdir(exist_ok=True)
            (tmp / name / key).write_bytes(data)
            sizes[name] += len(data)

    def load_pickle():
        for key in keys:
            with open(tmp / "pickle" / key, "rb") as fh:
                pickle.load(fh)

    def load_entry():
        for key in keys:
            cache._run_output(cache.read(tmp / "entry" / key, key, "RunOutput"))

    def load_npz():
        for key in keys:
            npz_load(tmp / "npz" / key, key)

    def digest_only():
        for key in keys:
            hashlib.sha256((tmp / "entry" / key).read_bytes())

    loaders = {"pickle": load_pickle, "entry": load_entry, "npz": load_npz, "sha256 of the entries": digest_only}
    times: dict = {name: [] for name in loaders}
    cpu: dict = {name: [] for name in loaders}
    for _ in range(args.rounds):
        for name, fn in loaders.items():
            start, start_cpu = time.perf_counter(), time.process_time()
            fn()
            times[name].append(time.perf_counter() - start)
            cpu[name].append(time.process_time() - start_cpu)
    print(f"{len(keys)} runs from {args.old_cache}")
    for name in loaders:
        size = f"{sizes[name] / 1e6:8.1f} MB" if name in sizes else " " * 11
        t, c = statistics.median(times[name]), statistics.median(cpu[name])
        print(f"{name:<22} {size}  read all: {t:6.2f} s wall, {c:6.2f} s CPU ({c / len(keys) * 1e6:5.0f} us CPU per entry)")
    shutil.rmtree(tmp)


if __name__ == "__main__":
    main()
