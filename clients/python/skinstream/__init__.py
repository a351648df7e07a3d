"""skinstream: subscribe to a skinstreamd and receive a subject's deforming body mesh as numpy
arrays, whatever encoding the daemon sends (float, quantised, compressed, or the per-part
deformation parameters, evaluated here). Protocol: docs/subscriber-protocol.md.

    import skinstream
    with skinstream.Subscriber('stage-pc', encoding='compressed', markers=True) as sub:
        for frame in sub.frames():
            print(frame.frame_number, frame.vertices[0])  # mm; sub.mesh.faces for the triangles

Receiver does the same on a background thread, keeps only the newest frame and reconnects with
backoff when the daemon goes away (for renderers with their own loop, such as Blender).

Compressed frames are decoded by the system's libmeshoptimizer and parameters evaluated by the
C++ client library (libskinstream_client) when they load, else in numpy: decoders() says which.
"""
from .decoder_choice import decoders
from .protocol import ENCODINGS, MARKER_STATUS, Error, ProtocolError
from .point_cache import PointCacheWriter, read_point_cache
from .receiver import Receiver
from .subscriber import ConnectionLost, Frame, Refused, Subscriber
from .vertex_codec import CodecError

__version__ = '0.1.0'
__all__ = ['Subscriber', 'Receiver', 'Frame', 'Error', 'ProtocolError', 'ConnectionLost', 'Refused', 'CodecError',
           'PointCacheWriter', 'read_point_cache', 'ENCODINGS', 'MARKER_STATUS', 'decoders']
