"""PC2 point caches (Blender's Mesh Cache modifier, 3ds Max Point Cache): read and write.

A PC2 file is a 32-byte header (``POINTCACHE2\\0``, version 1, point count, start frame, sample
interval in frames, sample count) followed by float32 little-endian x, y, z per point per sample.
It carries positions only; the topology comes from a base mesh with the same vertex order (for a
drape: ``garment_0000.obj``, whose vertices are in the cache's order).
"""

from __future__ import annotations

import struct
from pathlib import Path

import numpy as np

from ..errors import TailorError
from .atomic import atomic_write

__all__ = ["read_pc2", "write_pc2"]

_MAGIC = b"POINTCACHE2\0"


def write_pc2(path, frames, *, start_frame: float = 0.0, sample_interval: float = 1.0) -> None:
    """Write ``frames`` (T, N, 3) [m] as a PC2 cache, atomically; non-finite positions are refused."""
    frames = np.asarray(frames, dtype=float)
    if frames.ndim != 3 or frames.shape[2] != 3:
        raise TailorError(f"{path}: PC2 frames must have shape (frames, points, 3), got {frames.shape}")
    if not np.all(np.isfinite(frames)):
        raise TailorError(f"{path}: refusing to write non-finite positions to PC2")
    header = _MAGIC + struct.pack("<iiffi", 1, frames.shape[1], start_frame, sample_interval, frames.shape[0])
    with atomic_write(path, "wb") as fh:
        fh.write(header)
        fh.write(np.ascontiguousarray(frames, dtype="<f4").tobytes())


def read_pc2(path, vertex_count: int | None = None, *, error=TailorError) -> np.ndarray:
    """Frames of a PC2 point cache, shape (T, N, 3); ``error`` is the exception class raised on bad files."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise error(f"{path.name}: cannot read: {exc.strerror or exc}") from None
    if len(data) < 32 or data[:12] != _MAGIC:
        raise error(f"{path.name}: not a PC2 point cache")
    _, n, _, _, samples = struct.unpack("<iiffi", data[12:32])
    if vertex_count is not None and n != vertex_count:
        raise error(f"{path.name}: {n} points per frame, but the base mesh has {vertex_count} vertices")
    values = np.frombuffer(data[32:], dtype="<f4")
    if len(values) != samples * n * 3:
        raise error(f"{path.name}: truncated ({len(values)} floats for {samples} frames of {n} points)")
    return values.reshape(samples, n, 3).astype(float)
