"""A decoder of meshoptimizer's vertex codec, version 0, in numpy: the format of
meshopt_encodeVertexBuffer in meshoptimizer 0.18 (which every later decoder also reads), and of
the compressed encoding's blocks. Written from the format, checked byte for byte against the
library (tests/clients/python/vertex_codec_test.py).

The format:
- one byte 0xA0 (0xA0 | version);
- the vertices in blocks of B = min(256, 8192 // vertex_size rounded down to a multiple of 16);
- per block, per byte k of the vertex: the block's deltas of byte k (the byte minus the same
  byte of the vertex before, mod 256, zigzagged: d -> 2d, -d -> 2d - 1), zeros after the last
  vertex up to a multiple of 16, in groups of 16: first (groups + 3) // 4 header bytes, 2 bits a
  group (group g in bits 2 (g % 4) of byte g // 4): 0 sixteen zeros, no bytes; 1 sixteen 2-bit
  values in 4 bytes; 2 sixteen 4-bit values in 8 bytes; 3 sixteen bytes as they are. Packed
  values fill each byte from its high bits; an all-ones value (3, 15) stands for a byte that
  follows the group's packed bytes, in order;
- the tail: zeros up to 32 - vertex_size bytes, then the first vertex, which is also the
  "vertex before" the first.

The groups' sizes depend on their contents, so finding them is a walk (plain Python, one step
a group that is not all zeros); the values are then unpacked and summed in numpy.
"""
import numpy as np

HEADER = 0xA0
_TAIL = 32
_GROUP = 16


class CodecError(ValueError):
    """A buffer the vertex codec's decoder refuses (meshopt_decodeVertexBuffer would return non-zero)."""


def _sentinel_windows(data, sentinel_lut, width):
    """Bytes: at each offset, how many sentinels a group packed in the `width` bytes from there holds."""
    counts = sentinel_lut[data].astype(np.int32)
    sums = np.concatenate(([0], np.cumsum(counts)))
    windows = sums[np.minimum(np.arange(len(data)) + width, len(data))] - sums[:len(data)]
    return windows.astype(np.uint8).tobytes()


_BYTE = np.arange(256)
_SENTINELS_2 = sum(((_BYTE >> s) & 3) == 3 for s in (0, 2, 4, 6)).astype(np.uint8)
_SENTINELS_4 = sum(((_BYTE >> s) & 15) == 15 for s in (0, 4)).astype(np.uint8)
_LANE = np.arange(_GROUP)


def block_size(vertex_size):
    return min(256, (8192 // vertex_size) & ~(_GROUP - 1))


def decode_vertex_buffer(buffer, vertex_count, vertex_size):
    """The vertex_count x vertex_size uint8 array coded in `buffer`; CodecError on bad data."""
    if vertex_size <= 0 or vertex_size > 256 or vertex_size % 4:
        raise ValueError(f'vertex size {vertex_size} (a multiple of 4 up to 256)')
    data = bytes(buffer)
    tail = max(_TAIL, vertex_size)
    if len(data) < 1 + tail:
        raise CodecError(f'vertex codec stream of {len(data)} bytes is truncated')
    if data[0] & 0xF0 != HEADER:
        raise CodecError(f'not a vertex codec stream (header byte 0x{data[0]:02x})')
    if data[0] != HEADER:
        raise CodecError(f'vertex codec version {data[0] & 0x0F} (this decoder reads version 0)')
    array = np.frombuffer(data, np.uint8)
    first = array[len(data) - vertex_size:]
    end = len(data) - tail
    size = block_size(vertex_size)
    blocks = -(-vertex_count // size)
    full_groups = size // _GROUP
    windows2 = _sentinel_windows(array, _SENTINELS_2, 4)
    windows4 = _sentinel_windows(array, _SENTINELS_4, 8)

    # The walk: where each group that is not all zeros starts, as start << 34 | group << 2 | bits code.
    found = []
    keep = found.append
    at = 1
    try:
        for b in range(blocks):
            groups = (min(size, vertex_count - b * size) + _GROUP - 1) // _GROUP
            header_bytes = (groups + 3) // 4
            for k in range(vertex_size):
                header = int.from_bytes(data[at:at + header_bytes], 'little')
                at += header_bytes
                g = (b * vertex_size + k) * full_groups << 2
                while header:
                    code = header & 3
                    if code:
                        keep(at << 34 | g | code)
                        at += 16 if code == 3 else (4 + windows2[at] if code == 1 else 8 + windows4[at])
                    header >>= 2
                    g += 4
                if at > end:
                    raise IndexError
    except IndexError:
        raise CodecError(f'vertex codec stream truncated: {vertex_count} vertices of {vertex_size} bytes need more than '
                         f'{len(data)} bytes') from None
    if at != end:
        raise CodecError(f'vertex codec stream: {end - at} bytes between the last block and the tail')
    found = np.array(found, np.int64)
    codes, groups_found, starts_found = found & 3, (found >> 2) & ((1 << 32) - 1), found >> 34

    deltas = np.zeros((blocks * vertex_size * full_groups, _GROUP), np.uint8)
    for code, bits in ((1, 2), (2, 4), (3, 8)):
        chosen = codes == code
        if not chosen.any():
            continue
        index, starts = groups_found[chosen], starts_found[chosen][:, None]
        if bits == 8:
            deltas[index] = array[starts + _LANE]
            continue
        per_byte = 8 // bits
        packed = array[starts + _LANE // per_byte]
        values = (packed >> ((per_byte - 1 - _LANE % per_byte) * bits).astype(np.uint8)) & ((1 << bits) - 1)
        sentinel = values == (1 << bits) - 1
        extra = starts + 2 * bits + np.cumsum(sentinel, axis=1) - 1  # 2 * bits: the packed bytes (4 or 8)
        deltas[index] = np.where(sentinel, array[np.minimum(extra, len(data) - 1)], values)
    deltas = (np.uint8(0) - (deltas & 1)) ^ (deltas >> 1)  # unzigzag
    deltas = deltas.reshape(blocks, vertex_size, size).transpose(0, 2, 1).reshape(blocks * size, vertex_size)
    vertices = np.cumsum(deltas[:vertex_count], axis=0, dtype=np.uint8)
    vertices += first
    return vertices


def decode_octahedral(vertices):
    """Unit float32 vectors (n x 3) of 8-bit octahedral vectors (n x 4 int8: x, y, 127, 0), as
    meshopt_decodeFilterOct rounds them to 8 bits, then made unit again."""
    v = vertices.view(np.int8).astype(np.float32)
    x, y = v[:, 0], v[:, 1]
    z = v[:, 2] - np.abs(x) - np.abs(y)
    t = np.minimum(z, np.float32(0))
    x = x + np.where(x >= 0, t, -t)
    y = y + np.where(y >= 0, t, -t)
    with np.errstate(divide='ignore', invalid='ignore'):
        scale = np.float32(127) / np.sqrt(x * x + y * y + z * z)
        rounded = np.stack([c * scale + np.where(c >= 0, np.float32(0.5), np.float32(-0.5)) for c in (x, y, z)], axis=1)
        rounded = np.nan_to_num(rounded).astype(np.int32).astype(np.float32)  # toward zero, as C's int()
        rx, ry, rz = rounded[:, 0], rounded[:, 1], rounded[:, 2]
        length = np.sqrt(rx * rx + ry * ry + rz * rz)
        inverse = np.where(length > 0, np.float32(1) / length, np.float32(0))
    return rounded * inverse[:, None]
