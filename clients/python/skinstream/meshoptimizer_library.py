"""meshoptimizer's own decoders of the compressed encoding, from the system's shared library
through ctypes: the vertex codec (meshopt_decodeVertexBuffer) and the octahedral filter
(meshopt_decodeFilterOct), as the C++ client library decodes them. Debian and Ubuntu ship the
library as libmeshoptimizer2d (libmeshoptimizer.so.2d); any meshoptimizer from 0.18 on reads
the daemon's streams. Without it the package decodes in numpy (vertex_codec.py)."""
import ctypes
import ctypes.util
import functools

import numpy as np

from .vertex_codec import CodecError, decode_vertex_buffer

_size = ctypes.c_size_t


class MeshoptimizerLibrary:
    """The library's decoders; name says which file was loaded."""

    def __init__(self, path):
        library = ctypes.CDLL(path)
        self.name = path
        self._decode = library.meshopt_decodeVertexBuffer
        self._decode.argtypes = [ctypes.c_void_p, _size, _size, ctypes.c_void_p, _size]
        self._decode.restype = ctypes.c_int
        self._filter_oct = library.meshopt_decodeFilterOct
        self._filter_oct.argtypes = [ctypes.c_void_p, _size, _size]
        self._filter_oct.restype = None

    def decode_vertex_buffer(self, coded, vertex_count, vertex_size):
        """The vertex_count x vertex_size uint8 array coded in `coded` (bytes-like); CodecError on
        bad data, naming what is wrong as the numpy decoder finds it."""
        if vertex_size <= 0 or vertex_size > 256 or vertex_size % 4:
            raise ValueError(f'vertex size {vertex_size} (a multiple of 4 up to 256)')  # the library would assert
        source = np.frombuffer(coded, np.uint8)
        out = np.empty((vertex_count, vertex_size), np.uint8)
        if self._decode(out.ctypes.data, vertex_count, vertex_size, source.ctypes.data, len(source)) != 0:
            decode_vertex_buffer(coded, vertex_count, vertex_size)  # raises CodecError saying why
            raise CodecError('the vertex codec stream does not decode')
        return out

    def decode_octahedral(self, vertices):
        """Unit float32 vectors (n x 3) of 8-bit octahedral vectors (n x 4 bytes: x, y, 127, 0,
        as decoded; filtered in place): the library's filter, then made unit again as the C++
        client does."""
        filtered = np.ascontiguousarray(vertices).view(np.int8)
        self._filter_oct(filtered.ctypes.data, len(filtered), 4)
        v = filtered.ravel().astype(np.float32)
        x, y, z = v[0::4], v[1::4], v[2::4]  # one long loop each, not V loops over 3 columns
        length = np.sqrt(x * x + y * y + z * z)
        with np.errstate(divide='ignore'):
            scale = np.where(length > 0, np.float32(1) / length, np.float32(0))
        unit = np.empty((len(filtered), 3), np.float32)
        for axis, component in enumerate((x, y, z)):
            np.multiply(component, scale, out=unit[:, axis])
        return unit


@functools.lru_cache(maxsize=None)
def find_meshoptimizer():
    """(MeshoptimizerLibrary or None, one line saying which library, or why none)."""
    path = ctypes.util.find_library('meshoptimizer')
    if path is None:
        return None, 'libmeshoptimizer not found (Debian: apt-get install libmeshoptimizer2d)'
    try:
        return MeshoptimizerLibrary(path), path
    except (OSError, AttributeError) as e:
        return None, f'{path} does not load: {e}'
