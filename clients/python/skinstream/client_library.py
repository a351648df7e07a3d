"""The parameter encoding evaluated by the C++ client library (libskinstream_client, its C ABI in
clients/cpp/include/skinstream/evaluator_c.h) through ctypes: the daemon's own evaluator, so
the vertices and normals are the daemon's float buffers bit for bit, in about a millisecond a
frame. The library is found by the path in the environment variable SKINSTREAM_CLIENT_LIBRARY,
else by name (ctypes.util.find_library: an installed, ldconfig'd libskinstream_client.so.0).
The calls release Python's interpreter lock: other threads run while a frame evaluates."""
import ctypes
import ctypes.util
import functools
import os

import numpy as np

from .evaluation import read_parameters
from .protocol import ProtocolError

ENVIRONMENT = 'SKINSTREAM_CLIENT_LIBRARY'
ABI_VERSION = 1  # SKINSTREAM_EVALUATOR_ABI_VERSION this module was written for
_ERROR_BYTES = 512


class ClientLibrary:
    """libskinstream_client's evaluator functions; name says which file was loaded."""

    def __init__(self, path):
        library = ctypes.CDLL(path)
        self.name = path
        library.skinstream_evaluator_abi_version.restype = ctypes.c_uint32
        library.skinstream_evaluator_abi_version.argtypes = []
        version = library.skinstream_evaluator_abi_version()
        if version != ABI_VERSION:
            raise OSError(f'evaluator ABI version {version}, this package speaks {ABI_VERSION}')
        self.create = library.skinstream_evaluator_create
        self.create.restype = ctypes.c_void_p
        self.create.argtypes = [ctypes.c_void_p, ctypes.c_size_t, ctypes.c_void_p, ctypes.c_size_t, ctypes.c_char_p, ctypes.c_size_t]
        self.vertex_count = library.skinstream_evaluator_vertex_count
        self.vertex_count.restype = ctypes.c_uint32
        self.vertex_count.argtypes = [ctypes.c_void_p]
        self.evaluate = library.skinstream_evaluator_evaluate
        self.evaluate.restype = ctypes.c_int
        self.evaluate.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t, ctypes.c_void_p, ctypes.c_void_p,
                                  ctypes.c_char_p, ctypes.c_size_t]
        self.destroy = library.skinstream_evaluator_destroy
        self.destroy.restype = None
        self.destroy.argtypes = [ctypes.c_void_p]


class LibraryEvaluator:
    """The numpy Evaluator's interface (evaluation.py) over the library: evaluate(block, normals)."""

    name = 'libskinstream_client'

    def __init__(self, library, model, payload, faces=None):
        """`payload`: the Model message's payload that `model` (protocol.Model) was read from;
        `faces`: MeshInfo's F x 3 triangles (None: no normals)."""
        self.model = model
        self._library = library
        self._handle = None
        source = np.frombuffer(payload, np.uint8)
        self._faces = None if faces is None else np.ascontiguousarray(faces, np.uint32)
        faces_pointer, face_count = (None, 0) if self._faces is None else (self._faces.ctypes.data, len(self._faces))
        error = ctypes.create_string_buffer(_ERROR_BYTES)
        handle = library.create(source.ctypes.data, len(source), faces_pointer, face_count, error, _ERROR_BYTES)
        if not handle:
            raise ProtocolError(error.value.decode('utf-8', 'replace'))
        self._handle = handle
        if library.vertex_count(handle) != model.vertex_count:
            raise ProtocolError(f'the library reads {library.vertex_count(handle)} vertices in the Model, '
                                f'this package {model.vertex_count}')

    def __del__(self):
        if self._handle:
            self._library.destroy(self._handle)
            self._handle = None

    def parameters(self, block):
        """(parts, weights) of a Frame's parameters block, checked against the Model."""
        return read_parameters(self.model, block)

    def evaluate(self, block, normals=False):
        """(vertices, normals): V x 3 float32 (normals None unless asked for and the faces known)."""
        self.parameters(block)  # the same one-line errors as the numpy evaluator's
        count = self.model.vertex_count
        vertices = np.empty((count, 3), np.float32)
        unit = np.empty((count, 3), np.float32) if normals and self._faces is not None else None
        source = np.frombuffer(block, np.uint8)
        error = ctypes.create_string_buffer(_ERROR_BYTES)
        if self._library.evaluate(self._handle, source.ctypes.data, len(source), vertices.ctypes.data,
                                  None if unit is None else unit.ctypes.data, error, _ERROR_BYTES):
            raise ProtocolError(error.value.decode('utf-8', 'replace'))
        return vertices, unit


@functools.lru_cache(maxsize=None)
def find_client_library():
    """(ClientLibrary or None, one line saying which library, or why none)."""
    path = os.environ.get(ENVIRONMENT) or ctypes.util.find_library('skinstream_client')
    if not path:
        return None, (f'libskinstream_client not found (install clients/cpp with cmake --install and run ldconfig, or set '
                      f'{ENVIRONMENT} to its path)')
    try:
        return ClientLibrary(path), path
    except (OSError, AttributeError) as e:
        return None, f'{path} does not load: {e}'
