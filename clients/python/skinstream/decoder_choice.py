"""Which decoder turns each encoding into vertices here: the system's shared libraries through
ctypes when they load (libmeshoptimizer for the compressed encoding, the C++ client library
libskinstream_client for the parameters), else numpy, which always works."""
from .client_library import LibraryEvaluator, find_client_library
from .compressed import CompressedDecoder
from .evaluation import Evaluator
from .meshoptimizer_library import find_meshoptimizer


def compressed_decoder(vertex_count, order=None, libraries=True):
    """A CompressedDecoder: libmeshoptimizer's when `libraries` and it loads, else numpy's."""
    return CompressedDecoder(vertex_count, order, find_meshoptimizer()[0] if libraries else None)


def parameter_evaluator(model, payload, faces=None, libraries=True):
    """An evaluator of the Model (protocol.Model, read from `payload`): libskinstream_client's
    when `libraries` and it loads, else numpy's. ProtocolError when the library refuses it."""
    library = find_client_library()[0] if libraries else None
    return Evaluator(model, faces) if library is None else LibraryEvaluator(library, model, payload, faces)


def decoders():
    """{encoding: one line saying what decodes it here, and how to get the library where numpy does}."""
    meshoptimizer, meshoptimizer_line = find_meshoptimizer()
    client, client_line = find_client_library()
    return {'float': 'numpy (views of the message)', 'quantised': 'numpy',
            'compressed': f'libmeshoptimizer ({meshoptimizer_line})' if meshoptimizer else f'numpy; {meshoptimizer_line}',
            'parameters': f'libskinstream_client ({client_line})' if client else f'numpy; {client_line}'}
