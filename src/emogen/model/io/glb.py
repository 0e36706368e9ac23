"""The glTF 2.0 container: GLB bytes in and out, and typed accessors over its buffers.

Written by hand rather than through pygltflib: the JSON is a plain dict, so nothing writes
fields the spec forbids (pygltflib puts ``byteOffset: 0`` on sparse accessors that have no
bufferView, which the Khronos validator rejects), and every bufferView starts 4-byte aligned.
"""

from __future__ import annotations

import base64
import hashlib
import json
import struct
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from urllib.parse import unquote

import numpy as np

from emogen.errors import ModelFileError

GLB_MAGIC = b"glTF"
CHUNK_JSON = 0x4E4F534A
CHUNK_BIN = 0x004E4942

BYTE, UNSIGNED_BYTE, SHORT, UNSIGNED_SHORT, UNSIGNED_INT, FLOAT = 5120, 5121, 5122, 5123, 5125, 5126
ARRAY_BUFFER, ELEMENT_ARRAY_BUFFER = 34962, 34963

DTYPES: dict[int, np.dtype] = {
    BYTE: np.dtype("<i1"),
    UNSIGNED_BYTE: np.dtype("<u1"),
    SHORT: np.dtype("<i2"),
    UNSIGNED_SHORT: np.dtype("<u2"),
    UNSIGNED_INT: np.dtype("<u4"),
    FLOAT: np.dtype("<f4"),
}
COMPONENT_TYPES = {dt: code for code, dt in DTYPES.items()}
N_COMPONENTS = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT2": 4, "MAT3": 9, "MAT4": 16}
TYPES = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4"}
# Largest magnitude of a normalized integer: value = max(c / NORM, -1) (glTF 2.0 §3.11).
NORM = {BYTE: 127.0, UNSIGNED_BYTE: 255.0, SHORT: 32767.0, UNSIGNED_SHORT: 65535.0}


def _pad4(n: int) -> int:
    return (n + 3) & ~3


# ---- writing --------------------------------------------------------------------------------
@dataclass
class _Pool:
    """One bufferView that several accessors share, filled piece by piece."""

    view: int
    stride: int | None
    target: int | None
    data: bytearray = field(default_factory=bytearray)

    def append(self, raw: bytes) -> int:
        self.data.extend(b"\0" * (_pad4(len(self.data)) - len(self.data)))
        offset = len(self.data)
        self.data.extend(raw)
        return offset


class GlbBuilder:
    """Accumulates accessors in a few shared bufferViews and writes one GLB.

    Vertex attributes whose elements are not a multiple of 4 bytes (int16 and int8 VEC3) are
    padded to a 4-byte stride, as the spec requires; sparse indices and values are packed.
    """

    def __init__(self) -> None:
        self.accessors: list[dict[str, Any]] = []
        self._pools: dict[tuple[str, int | None, int | None], _Pool] = {}

    def _pool(self, kind: str, stride: int | None = None, target: int | None = None) -> _Pool:
        key = (kind, stride, target)
        if key not in self._pools:
            self._pools[key] = _Pool(len(self._pools), stride, target)
        return self._pools[key]

    def _add(self, accessor: dict[str, Any]) -> int:
        self.accessors.append(accessor)
        return len(self.accessors) - 1

    def attribute(
        self, values: np.ndarray, *, normalized: bool = False, min_max: bool = False
    ) -> int:
        """A dense vertex attribute accessor from (n, k) values of their final dtype."""
        n, k = values.shape
        item = values.dtype.itemsize * k
        stride = _pad4(item)
        padded = np.zeros((n, stride), dtype=np.uint8)
        padded[:, :item] = np.ascontiguousarray(values).view(np.uint8).reshape(n, item)
        pool = self._pool("attributes", stride, ARRAY_BUFFER)
        acc = self._accessor_header(values, normalized, min_max)
        acc.update(bufferView=pool.view, byteOffset=pool.append(padded.tobytes()))
        return self._add(acc)

    def indices(self, triangles: np.ndarray, n_vertices: int) -> int:
        # 65535 is the primitive-restart value of unsigned short indices: keep below it.
        dtype = np.dtype("<u2") if n_vertices < 65535 else np.dtype("<u4")
        flat = np.ascontiguousarray(triangles.reshape(-1), dtype=dtype)
        pool = self._pool("indices", None, ELEMENT_ARRAY_BUFFER)
        return self._add(
            {
                "bufferView": pool.view,
                "byteOffset": pool.append(flat.tobytes()),
                "componentType": COMPONENT_TYPES[dtype],
                "count": len(flat),
                "type": "SCALAR",
            }
        )

    def blob(self, data: bytes) -> int:
        """A bufferView of its own holding ``data`` as is (an embedded image); its index."""
        pool = self._pool(f"blob{len(self._pools)}")
        pool.append(data)
        return pool.view

    def sparse(self, values: np.ndarray, *, normalized: bool = False, min_max: bool = False) -> int:
        """An accessor of (n, k) values, mostly zero, stored as sparse (or as zeros alone)."""
        acc = self._accessor_header(values, normalized, min_max)
        moved = np.flatnonzero(np.any(values != 0, axis=1))
        if len(moved):
            idx_dtype = np.dtype("<u2") if len(values) <= 65536 else np.dtype("<u4")
            ipool = self._pool("sparse_indices")
            vpool = self._pool("sparse_values")
            acc["sparse"] = {
                "count": len(moved),
                "indices": {
                    "bufferView": ipool.view,
                    "byteOffset": ipool.append(moved.astype(idx_dtype).tobytes()),
                    "componentType": COMPONENT_TYPES[idx_dtype],
                },
                "values": {
                    "bufferView": vpool.view,
                    "byteOffset": vpool.append(np.ascontiguousarray(values[moved]).tobytes()),
                },
            }
        return self._add(acc)

    @staticmethod
    def _accessor_header(values: np.ndarray, normalized: bool, min_max: bool) -> dict[str, Any]:
        acc: dict[str, Any] = {
            "componentType": COMPONENT_TYPES[values.dtype.newbyteorder("<")],
            "count": int(values.shape[0]),
            "type": TYPES[values.shape[1]],
        }
        if normalized:
            acc["normalized"] = True
        if min_max:
            as_num = float if values.dtype.kind == "f" else int
            lo = values.min(0) if len(values) else np.zeros(values.shape[1])
            hi = values.max(0) if len(values) else np.zeros(values.shape[1])
            acc["min"] = [as_num(x) for x in lo]
            acc["max"] = [as_num(x) for x in hi]
        return acc

    def finish(self, doc: dict[str, Any]) -> bytes:
        """GLB bytes of ``doc`` with this builder's accessors, bufferViews and buffer."""
        blob = bytearray()
        views = []
        for pool in sorted(self._pools.values(), key=lambda p: p.view):
            blob.extend(b"\0" * (_pad4(len(blob)) - len(blob)))
            view: dict[str, Any] = {
                "buffer": 0,
                "byteOffset": len(blob),
                "byteLength": len(pool.data),
            }
            if pool.stride is not None:
                view["byteStride"] = pool.stride
            if pool.target is not None:
                view["target"] = pool.target
            views.append(view)
            blob.extend(pool.data)
        doc = dict(doc, accessors=self.accessors, bufferViews=views)
        doc["buffers"] = [{"byteLength": len(blob)}]
        return glb_bytes(doc, bytes(blob))


def glb_bytes(doc: dict[str, Any], blob: bytes) -> bytes:
    """A GLB: 12-byte header, the JSON chunk (space-padded), the BIN chunk (zero-padded)."""
    text = json.dumps(doc, separators=(",", ":"), ensure_ascii=False).encode()
    text += b" " * (_pad4(len(text)) - len(text))
    blob = blob + b"\0" * (_pad4(len(blob)) - len(blob))
    total = 12 + 8 + len(text) + (8 + len(blob) if blob else 0)
    out = [
        struct.pack("<4sII", GLB_MAGIC, 2, total),
        struct.pack("<II", len(text), CHUNK_JSON),
        text,
    ]
    if blob:
        out += [struct.pack("<II", len(blob), CHUNK_BIN), blob]
    return b"".join(out)


# ---- reading --------------------------------------------------------------------------------
@dataclass(frozen=True)
class Gltf:
    """A parsed glTF asset: its JSON document and the bytes of each of its buffers."""

    path: Path
    doc: dict[str, Any]
    buffers: tuple[bytes, ...]
    digest: str  # sha256 of the file's bytes

    def accessor(self, index: int) -> np.ndarray:
        """Accessor ``index`` as (count, n_components): float64 for float and normalized
        integer data (dequantized), the stored integers otherwise; sparse values applied."""
        acc = self.doc["accessors"][index]
        ctype = acc["componentType"]
        dtype = DTYPES[ctype]
        k = N_COMPONENTS[acc["type"]]
        count = int(acc["count"])
        if "bufferView" in acc:
            out = self._read(acc["bufferView"], acc.get("byteOffset", 0), dtype, count, k).copy()
        else:
            out = np.zeros((count, k), dtype=dtype)
        sparse = acc.get("sparse")
        if sparse:
            n = int(sparse["count"])
            si, sv = sparse["indices"], sparse["values"]
            idx = self._read(
                si["bufferView"], si.get("byteOffset", 0), DTYPES[si["componentType"]], n, 1
            )
            vals = self._read(sv["bufferView"], sv.get("byteOffset", 0), dtype, n, k, tight=True)
            idx = idx[:, 0].astype(np.int64)
            if n and (idx.min() < 0 or idx.max() >= count):
                raise ValueError(f"accessor {index}: sparse index out of range")
            out[idx] = vals
        if ctype == FLOAT:
            return out.astype(np.float64)
        if acc.get("normalized", False):
            return np.maximum(out.astype(np.float64) / NORM[ctype], -1.0)
        return out

    def _read(
        self, view_index: int, offset: int, dtype: np.dtype, count: int, k: int, tight: bool = False
    ) -> np.ndarray:
        view = self.doc["bufferViews"][view_index]
        buf = self.buffers[view["buffer"]]
        start = view.get("byteOffset", 0) + offset
        item = dtype.itemsize * k
        stride = item if tight else view.get("byteStride", item) or item
        need = stride * (count - 1) + item if count else 0
        if offset + need > view["byteLength"] or start + need > len(buf):
            raise ValueError(f"bufferView {view_index} is too short for the data it should hold")
        if stride == item:
            return np.frombuffer(buf, dtype=dtype, count=count * k, offset=start).reshape(count, k)
        return np.ndarray(
            (count, k), dtype=dtype, buffer=buf, offset=start, strides=(stride, dtype.itemsize)
        )


def _read_file(path: Path) -> bytes:
    try:
        return path.read_bytes()
    except FileNotFoundError:
        raise ModelFileError(f"model file is missing: {path}") from None
    except OSError as exc:
        raise ModelFileError(f"cannot read model file {path}: {exc.strerror}") from None


def _split_glb(path: Path, data: bytes) -> tuple[dict[str, Any], bytes | None]:
    if len(data) < 20 or data[:4] != GLB_MAGIC:
        raise ModelFileError(f"{path}: not a GLB file (no 'glTF' magic at the start)")
    _, version, length = struct.unpack_from("<4sII", data)
    if version != 2:
        raise ModelFileError(f"{path}: GLB version {version}; only glTF 2.0 is supported")
    if length > len(data):
        raise ModelFileError(
            f"{path}: truncated GLB: header says {length} bytes, file has {len(data)}"
        )
    chunks: list[tuple[int, bytes]] = []
    pos = 12
    while pos + 8 <= length:
        size, kind = struct.unpack_from("<II", data, pos)
        if pos + 8 + size > length:
            raise ModelFileError(f"{path}: truncated GLB: a chunk runs past the end of the file")
        chunks.append((kind, data[pos + 8 : pos + 8 + size]))
        pos += 8 + _pad4(size)
    if not chunks or chunks[0][0] != CHUNK_JSON:
        raise ModelFileError(f"{path}: GLB has no JSON chunk first")
    try:
        doc = json.loads(chunks[0][1])
    except (UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ModelFileError(f"{path}: the GLB's JSON chunk is not valid JSON ({exc})") from None
    binary = chunks[1][1] if len(chunks) > 1 and chunks[1][0] == CHUNK_BIN else None
    return doc, binary


def _buffer_bytes(path: Path, buffer: dict[str, Any], binary: bytes | None) -> bytes:
    uri = buffer.get("uri")
    if uri is None:
        if binary is None:
            raise ModelFileError(f"{path}: a buffer has no uri and the file has no BIN chunk")
        return binary
    if uri.startswith("data:"):
        header, _, payload = uri.partition(",")
        if not header.endswith(";base64"):
            raise ModelFileError(f"{path}: data URI buffers must be base64")
        return base64.b64decode(payload)
    return _read_file(path.parent / unquote(uri))


def read_gltf(path: Path) -> Gltf:
    """Parse a ``.glb`` (or ``.gltf`` with its buffers); errors name the file."""
    data = _read_file(path)
    if data[:4] == GLB_MAGIC or path.suffix.lower() == ".glb":
        doc, binary = _split_glb(path, data)
    else:
        try:
            doc, binary = json.loads(data), None
        except (UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise ModelFileError(f"{path}: not valid glTF JSON ({exc})") from None
    if (
        not isinstance(doc, dict)
        or str(doc.get("asset", {}).get("version", "")).split(".")[0] != "2"
    ):
        raise ModelFileError(f"{path}: not a glTF 2.0 asset (asset.version must be '2.0')")
    buffers = tuple(_buffer_bytes(path, b, binary) for b in doc.get("buffers", []))
    for i, (b, spec) in enumerate(zip(buffers, doc.get("buffers", []), strict=True)):
        if len(b) < int(spec.get("byteLength", 0)):
            raise ModelFileError(
                f"{path}: buffer {i} holds {len(b)} bytes; the file declares {spec['byteLength']}"
            )
    return Gltf(path, doc, buffers, hashlib.sha256(data).hexdigest())


def read_glb_json(path: Path) -> dict[str, Any]:
    """Only the JSON document of a GLB (cheap: for its extras)."""
    return _split_glb(path, _read_file(path))[0]
