"""Tone map and PNG writing (zlib and struct only: no imaging library in the core).

Tone map: `srgb(clamp(radiance × exposure, 0, 1))`, with sRGB's piecewise encoding and rounding
to 8 bits.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import numpy as np


def tone_map(radiance: np.ndarray, exposure: float) -> np.ndarray:
    """Linear radiance -> 8-bit sRGB: scale by exposure, clamp to [0, 1], sRGB-encode, round."""
    x = np.clip(radiance * exposure, 0.0, 1.0)
    encoded = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.round(encoded * 255).astype(np.uint8)


def png_bytes(rgb: np.ndarray) -> bytes:
    """An 8-bit RGB PNG of an (H, W, 3) uint8 array, row 0 at the top."""
    height, width, _ = rgb.shape
    rows = np.concatenate([np.zeros((height, 1), np.uint8), rgb.reshape(height, -1)], axis=1)  # filter 0

    def chunk(kind: bytes, data: bytes) -> bytes:
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
            + chunk(b"IDAT", zlib.compress(rows.tobytes(), 9)) + chunk(b"IEND", b""))


def write_png(path, rgb: np.ndarray) -> None:
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    Path(path).write_bytes(png_bytes(rgb))
