"""The PC2 point cache (3ds Max PointCache2): what Blender's Mesh Cache modifier plays back.
Little-endian, a 32-byte header: char[12] "POINTCACHE2\\0", int32 version 1, int32 point count,
float32 start frame, float32 sample rate (frames between samples), int32 sample count; then per
sample, per point, float32 x y z."""
import struct

import numpy as np

SIGNATURE = b'POINTCACHE2\0'
_HEADER = struct.Struct('<12siiffi')


class PointCacheWriter:
    """Appends samples as they come; the header's sample count is written at close()."""

    def __init__(self, path, point_count, start_frame=0.0, sample_rate=1.0):
        if point_count <= 0:
            raise ValueError(f'{path}: a point cache needs at least one point, got {point_count}')
        self.path, self.point_count, self.sample_count = path, point_count, 0
        self._file = open(path, 'wb')
        self._file.write(_HEADER.pack(SIGNATURE, 1, point_count, start_frame, sample_rate, 0))

    def append(self, points):
        points = np.asarray(points, '<f4')
        if points.shape != (self.point_count, 3):
            raise ValueError(f'{self.path}: a sample of shape {points.shape}, the cache has {self.point_count} points')
        self._file.write(points.tobytes())
        self.sample_count += 1

    def close(self):
        if self._file.closed:
            return
        self._file.seek(28)
        self._file.write(struct.pack('<i', self.sample_count))
        self._file.close()

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def read_point_cache(path):
    """(start frame, sample rate, samples as a sample_count x point_count x 3 float32 array);
    ValueError naming what is wrong with the file."""
    with open(path, 'rb') as f:
        data = f.read()
    if len(data) < _HEADER.size:
        raise ValueError(f'{path}: truncated: {len(data)} bytes, a PC2 header has 32')
    signature, version, points, start, rate, samples = _HEADER.unpack_from(data)
    if signature != SIGNATURE:
        raise ValueError(f'{path}: not a PC2 point cache (no POINTCACHE2 signature)')
    if version != 1 or points < 0 or samples < 0:
        raise ValueError(f'{path}: PC2 version {version}, {points} points, {samples} samples (version 1, counts >= 0 are read)')
    expected = _HEADER.size + 12 * points * samples
    if len(data) != expected:
        raise ValueError(f'{path}: the header says {expected} bytes, the file has {len(data)}')
    return start, rate, np.frombuffer(data, '<f4', offset=_HEADER.size).reshape(samples, points, 3)
