"""meshoptimizer's own encoders (Debian's libmeshoptimizer, loaded with ctypes), for the tests of
the decoders: the vertex codec and the octahedral filter. `library` is None when it is missing."""
import ctypes
import ctypes.util

import numpy as np

_name = ctypes.util.find_library('meshoptimizer')
library = ctypes.CDLL(_name) if _name else None
if library:
    library.meshopt_encodeVertexBufferBound.restype = ctypes.c_size_t
    library.meshopt_encodeVertexBuffer.restype = ctypes.c_size_t
    library.meshopt_decodeVertexBuffer.restype = ctypes.c_int
MISSING = 'libmeshoptimizer is not installed (scripts/install-deps.sh installs it)'


def pointer(a):
    return a.ctypes.data_as(ctypes.c_void_p)


def encode(vertices):
    """meshopt_encodeVertexBuffer of an n x size uint8 array."""
    n, size = vertices.shape
    vertices = np.ascontiguousarray(vertices)
    bound = library.meshopt_encodeVertexBufferBound(ctypes.c_size_t(n), ctypes.c_size_t(size))
    out = np.zeros(bound, np.uint8)
    written = library.meshopt_encodeVertexBuffer(pointer(out), ctypes.c_size_t(bound), pointer(vertices), ctypes.c_size_t(n),
                                                 ctypes.c_size_t(size))
    assert written > 0
    return out[:written].tobytes()


def encode_octahedral(normals):
    """meshopt_encodeFilterOct of n x 3 unit vectors into 8 bits: n x 4 int8 (x, y, 127, 0)."""
    n = len(normals)
    padded = np.zeros((n, 4), np.float32)
    padded[:, :3] = normals
    out = np.zeros((n, 4), np.int8)
    library.meshopt_encodeFilterOct(pointer(out), ctypes.c_size_t(n), ctypes.c_size_t(4), 8, pointer(padded))
    return out
