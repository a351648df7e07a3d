"""The compressed encoding's positions and normals (docs/subscriber-protocol.md, "Compressed
positions and normals"): 16-bit positions on a grid fixed from one key frame to the next, delta
frames as their difference from the key, both coded with meshoptimizer's vertex codec; normals
as 8-bit octahedral vectors, every frame on its own. Decoded by the system's libmeshoptimizer
when one is given (meshoptimizer_library.py), else by the package's numpy decoder."""
import struct

import numpy as np

from .protocol import ProtocolError, padding_to_4
from .vertex_codec import CodecError, decode_octahedral, decode_vertex_buffer

_POSITION_HEADER = struct.Struct('<I3f3fI')  # key frame number, origin, step, coded bytes


class CompressedDecoder:
    """Holds the latest key frame's grid positions; a subscriber keeps one. `order`: the vertex
    of each coded vertex (MeshInfo's compressed order); `library`: a MeshoptimizerLibrary, or
    None for numpy; name says which decodes."""

    def __init__(self, vertex_count, order=None, library=None):
        self.vertex_count = vertex_count
        self.library = library
        self.name = 'numpy' if library is None else 'libmeshoptimizer'
        coded_index = np.arange(vertex_count)
        if order is not None:
            coded_index[np.asarray(order, np.int64)] = np.arange(vertex_count)
        # Flat gathers from the coded vertices (4 or 3 values each) into the mesh's order: numpy
        # runs one long loop over them, where row-wise work on 3 or 4 columns runs V short loops.
        self._from_quads = ((4 * coded_index)[:, None] + np.arange(3)).ravel()
        self._from_triples = ((3 * coded_index)[:, None] + np.arange(3)).ravel()
        self.key_frame_number = None  # of the key held
        self._key_q = None
        self._origin = self._step = None

    def decode(self, positions_block, normals_block, key):
        """(positions, normals) as V x 3 float32 (normals None when not sent), or None for a
        delta frame of a key this decoder has not seen: skip it until the next key frame."""
        if len(positions_block) < _POSITION_HEADER.size:
            raise ProtocolError('compressed positions: block truncated')
        fields = _POSITION_HEADER.unpack_from(positions_block)
        key_frame_number, origin, step, coded = fields[0], np.float32(fields[1:4]), np.float32(fields[4:7]), fields[7]
        if _POSITION_HEADER.size + coded + padding_to_4(coded) != len(positions_block):
            raise ProtocolError(f'compressed positions: {coded} coded bytes in a block of {len(positions_block)}')
        if not (np.isfinite(origin).all() and np.isfinite(step).all() and (step > 0).all()):
            raise ProtocolError("compressed positions: the grid's origin or step is not a finite positive number")
        if not key and (self._key_q is None or key_frame_number != self.key_frame_number):
            return None
        start = _POSITION_HEADER.size
        q = self._decode(positions_block[start:start + coded], 8, 'positions').view('<u2').ravel()  # x y z _ per vertex
        if key:
            self._key_q, self.key_frame_number, self._origin, self._step = q, key_frame_number, origin, step
        else:
            q = q + self._key_q  # mod 2^16
        positions = np.take(q, self._from_quads).astype(np.float32)
        for axis in range(3):
            column = positions[axis::3]
            column *= self._step[axis]
            column += self._origin[axis]
        normals = None
        if normals_block is not None and len(normals_block):
            if len(normals_block) < 4:
                raise ProtocolError('compressed normals: block truncated')
            (coded,) = struct.unpack_from('<I', normals_block)
            if 4 + coded + padding_to_4(coded) != len(normals_block):
                raise ProtocolError(f'compressed normals: {coded} coded bytes in a block of {len(normals_block)}')
            octahedral = self._decode(normals_block[4:4 + coded], 4, 'normals')
            unit = decode_octahedral(octahedral) if self.library is None else self.library.decode_octahedral(octahedral)
            normals = np.take(unit.ravel(), self._from_triples).reshape(-1, 3)
        return positions.reshape(-1, 3), normals

    def _decode(self, coded, vertex_size, what):
        try:
            if self.library is not None:
                return self.library.decode_vertex_buffer(coded, self.vertex_count, vertex_size)
            return decode_vertex_buffer(coded, self.vertex_count, vertex_size)
        except CodecError as e:
            raise ProtocolError(f'compressed {what}: {e}') from None
