"""Shared fixtures: the `geltip` binary (the CLI the package must agree with), one
Simulator per session, and a PNG reader independent of geltip's own."""
import json
import os
import struct
import subprocess
import sys
import zlib
from pathlib import Path

import numpy as np
import pytest

import geltip

REPO = Path(__file__).resolve().parents[2]

os.environ.setdefault("XDG_RUNTIME_DIR", "/tmp")


def _find_cli():
    if os.environ.get("GELTIP_BIN"):
        return Path(os.environ["GELTIP_BIN"])
    built = [REPO / "target" / p / "geltip" for p in ("debug", "release")]
    built = [b for b in built if b.is_file()]
    if built:
        # The most recent build: the one made from the sources under test.
        return max(built, key=lambda b: b.stat().st_mtime)
    subprocess.run(["cargo", "build", "--bin", "geltip"], cwd=REPO, check=True)
    return REPO / "target" / "debug" / "geltip"


@pytest.fixture(scope="session")
def cli():
    """Runs the geltip binary; returns its parsed JSON output (or raises with stderr)."""
    binary = _find_cli()

    def run(*args, check=True):
        p = subprocess.run([str(binary), *map(str, args)], capture_output=True, text=True)
        if not check:
            return p
        if p.returncode != 0:
            raise AssertionError(f"geltip {' '.join(map(str, args))}: {p.stderr}")
        return json.loads(p.stdout)

    return run


ALLSIGHT = REPO / ".." / "shared" / "real" / "allsight"


def run_example(name, *args):
    """python/examples/`name` with `args`, on the real AllSight set (the test is skipped
    where ../shared/real is absent): the finished process, its output captured."""
    if not (ALLSIGHT / "labels.json").is_file():
        pytest.skip(f"{ALLSIGHT} is absent (real sensor frames)")
    env = dict(os.environ, PYTHONPATH=str(REPO / "python"))
    return subprocess.run(
        [sys.executable, str(REPO / "python" / "examples" / name), "--real", str(ALLSIGHT),
         *map(str, args)],
        capture_output=True, text=True, env=env,
    )


@pytest.fixture(scope="session")
def sensor():
    return geltip.Sensor("paper")


@pytest.fixture(scope="session")
def sim(sensor):
    return geltip.Simulator(sensor)


def read_png(path):
    """8-bit RGB / RGBA / grey, non-interlaced PNG -> (H, W, C) uint8, in pure Python (so
    that comparisons with the CLI's files do not go through geltip's decoder)."""
    data = Path(path).read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, header = 8, b"", None
    while pos < len(data):
        (length,) = struct.unpack(">I", data[pos : pos + 4])
        kind = data[pos + 4 : pos + 8]
        body = data[pos + 8 : pos + 8 + length]
        pos += 12 + length
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            idat += body
        elif kind == b"IEND":
            break
    width, height, bits, colour, _, _, interlace = header
    assert bits == 8 and interlace == 0, (bits, interlace)
    channels = {0: 1, 2: 3, 4: 2, 6: 4}[colour]
    raw = zlib.decompress(idat)
    stride = width * channels
    out = np.zeros((height, stride), dtype=np.uint8)
    prev = np.zeros(stride, dtype=np.int32)
    for y in range(height):
        f = raw[y * (stride + 1)]
        line = np.frombuffer(raw, np.uint8, stride, y * (stride + 1) + 1).astype(np.int32)
        if f == 0:
            cur = line
        elif f == 2:
            cur = (line + prev) & 255
        else:  # 1 (sub), 3 (average), 4 (Paeth) depend on the pixel to the left
            cur = np.zeros(stride, dtype=np.int32)
            for i in range(stride):
                a = cur[i - channels] if i >= channels else 0
                b = prev[i]
                c = prev[i - channels] if i >= channels else 0
                if f == 1:
                    pred = a
                elif f == 3:
                    pred = (a + b) // 2
                else:
                    p = a + b - c
                    pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                    pred = a if pa <= pb and pa <= pc else (b if pb <= pc else c)
                cur[i] = (line[i] + pred) & 255
        out[y] = cur
        prev = cur
    return out.reshape(height, width, channels)


def write_png(path, rgb):
    """(H, W, 3) uint8 -> an 8-bit RGB PNG file, in pure Python (the package reads images
    but writes none)."""
    rgb = np.ascontiguousarray(rgb, dtype=np.uint8)
    height, width, _ = rgb.shape
    raw = b"".join(b"\x00" + rgb[y].tobytes() for y in range(height))

    def chunk(kind, body):
        crc = struct.pack(">I", zlib.crc32(kind + body))
        return struct.pack(">I", len(body)) + kind + body + crc

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    Path(path).write_bytes(
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", header)
        + chunk(b"IDAT", zlib.compress(raw, 1))
        + chunk(b"IEND", b"")
    )
