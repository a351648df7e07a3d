"""The live connection: a skinstream.Receiver reads the daemon on its own thread; a timer on
Blender's thread takes the newest frame (if any) and writes it into the body mesh, ~120 times a
second. Nothing here waits for the network, so Blender's UI never does."""
import os

import bpy
import numpy as np

try:
    from . import skinstream  # vendored in the add-on's zip (clients/blender/make_addon_zip.py)
except ImportError:
    import skinstream  # installed with pip, or clients/python on sys.path

BODY, MARKERS, MARKER_SHAPE, RECORDING = 'skinstream body', 'skinstream markers', 'skinstream marker', 'skinstream recording'
TICK_SECONDS = 1.0 / 120.0
MARKER_RADIUS_MM = 8.0


class _Connection:
    def __init__(self, receiver, scene_name):
        self.receiver = receiver
        self.scene_name = scene_name
        self.mesh_info = None  # the MeshInfo the body was built from
        self.body = self.markers = None  # object names
        self.frames_applied = 0
        self.frame_number = None  # of the frame applied last
        self.problem = ''  # the last thing that went wrong on Blender's side
        self.record_start = 0
        self.last_recording = ''


_connection = None


def connect(scene, host, port, encoding, subject='', token=''):
    global _connection
    disconnect()
    # Paced: at most two frames in flight, so a reader slower than the stream (the numpy
    # decoders, docs/connect-a-renderer.md) shows frames late by two at most, not by a socket's fill.
    receiver = skinstream.Receiver(host, port, encoding=encoding, subject=subject, token=token, normals=False, markers=True,
                                   paced=True, connect_timeout=2.0)
    receiver.start()
    _connection = _Connection(receiver, scene.name)
    if not bpy.app.timers.is_registered(apply_newest_frame):
        bpy.app.timers.register(apply_newest_frame, first_interval=0.0, persistent=True)


def disconnect():
    global _connection
    if bpy.app.timers.is_registered(apply_newest_frame):
        bpy.app.timers.unregister(apply_newest_frame)
    if _connection is not None:
        _connection.receiver.stop(timeout=0)  # the thread ends by itself; nothing waits for it here
        _connection = None


def connected():
    return _connection is not None


def frames_applied():
    return 0 if _connection is None else _connection.frames_applied


def body_object():
    return None if _connection is None or _connection.body is None else bpy.data.objects.get(_connection.body)


def status_lines():
    if _connection is None:
        return ['Not connected']
    c = _connection
    lines = [c.receiver.describe()]
    if c.frame_number is not None:
        lines.append(f'Frame {c.frame_number}: {c.frames_applied} shown, {c.receiver.frames_replaced} replaced by newer ones first')
    recording = c.receiver.recording()
    if recording is not None:
        path, samples, error = recording
        lines.append(f'Recording {os.path.basename(path)}: {samples} frames' + (f' ({error})' if error else ''))
    elif c.last_recording:
        lines.append(c.last_recording)
    if c.problem:
        lines.append(c.problem)
    return lines


def apply_newest_frame():
    """The timer: the newest frame into the body (and markers); returns when to run again."""
    if _connection is None:
        return None
    c = _connection
    try:
        scene = bpy.data.scenes.get(c.scene_name)
        info, model = c.receiver.mesh, c.receiver.model
        frame = c.receiver.take()
        if frame is not None:
            info = frame.mesh
        if scene is not None and info is not None and info is not c.mesh_info:
            reference = model.reference if model is not None and model.vertex_count == info.vertex_count else None
            if reference is not None or (frame is not None and frame.vertices is not None):
                _build_body(scene, info, reference if reference is not None else frame.vertices)
        if frame is not None and info is c.mesh_info:
            _apply(scene, frame)
    except Exception as e:  # e.g. objects deleted by the user; a timer that raised would be dropped by Blender
        c.problem = f'{type(e).__name__}: {e}'
        c.mesh_info = None  # built again from the next frame
    _redraw()
    return TICK_SECONDS


def _apply(scene, frame):
    c = _connection
    body = bpy.data.objects.get(c.body)
    if body is None:
        c.mesh_info = None  # deleted by the user: built again from the next frame
        return
    if frame.vertices is not None:
        body.data.vertices.foreach_set('co', frame.vertices.ravel())
        body.data.update()
    body['skinstream_frame'] = frame.frame_number
    if frame.markers is not None and len(frame.markers) and scene.skinstream.show_markers:
        _update_markers(scene, frame.markers)
    c.frames_applied += 1
    c.frame_number = frame.frame_number


def _build_body(scene, info, positions):
    """The body mesh from MeshInfo's triangles, at `positions` (the Model's reference pose, or
    the first frame)."""
    c = _connection
    v, f = info.vertex_count, len(info.faces)
    mesh = bpy.data.meshes.new(BODY)
    mesh.vertices.add(v)
    mesh.loops.add(3 * f)
    mesh.polygons.add(f)
    mesh.vertices.foreach_set('co', np.ascontiguousarray(positions, np.float32).ravel())
    mesh.loops.foreach_set('vertex_index', info.faces.astype(np.int32).ravel())
    mesh.polygons.foreach_set('loop_start', np.arange(0, 3 * f, 3, dtype=np.int32))
    mesh.polygons.foreach_set('loop_total', np.full(f, 3, np.int32))
    mesh.polygons.foreach_set('use_smooth', np.ones(f, bool))
    mesh.update()
    body = bpy.data.objects.get(c.body) if c.body else None
    if body is None:
        body = bpy.data.objects.new(BODY, mesh)
        scene.collection.objects.link(body)
    else:
        old, body.data = body.data, mesh
        if old.users == 0:
            bpy.data.meshes.remove(old)
    body.scale = (scene.skinstream.scale,) * 3
    body['skinstream_subject'] = info.subject
    c.body, c.mesh_info = body.name, info


def _update_markers(scene, markers):
    c = _connection
    holder = bpy.data.objects.get(c.markers) if c.markers else None
    if holder is None or len(holder.data.vertices) != len(markers):
        mesh = bpy.data.meshes.new(MARKERS)
        mesh.vertices.add(len(markers))
        if holder is None:
            holder = bpy.data.objects.new(MARKERS, mesh)
            scene.collection.objects.link(holder)
            holder.instance_type = 'VERTS'  # a sphere at every marker
            holder.show_instancer_for_viewport = False
            shape = bpy.data.objects.new(MARKER_SHAPE, _sphere(MARKER_RADIUS_MM))
            scene.collection.objects.link(shape)
            shape.parent = holder
        else:
            old, holder.data = holder.data, mesh
            if old.users == 0:
                bpy.data.meshes.remove(old)
        holder.scale = (scene.skinstream.scale,) * 3
        c.markers = holder.name
    holder.data.vertices.foreach_set('co', np.ascontiguousarray(markers, np.float32).ravel())
    holder.data.update()


def _sphere(radius):
    """An octahedron of the radius: enough to see a marker at any distance."""
    mesh = bpy.data.meshes.new(MARKER_SHAPE)
    corners = [(radius, 0, 0), (-radius, 0, 0), (0, radius, 0), (0, -radius, 0), (0, 0, radius), (0, 0, -radius)]
    faces = [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5), (0, 3, 5)]
    mesh.from_pydata(corners, [], faces)
    return mesh


def show_markers(show):
    holder = bpy.data.objects.get(_connection.markers) if _connection is not None and _connection.markers else None
    if holder is not None:
        holder.hide_viewport = holder.hide_render = not show


def can_record():
    return _connection is not None and _connection.receiver.recording() is None and _connection.mesh_info is not None


def recording():
    return None if _connection is None else _connection.receiver.recording()


def start_recording(path, scene_frame):
    """None, or why it cannot start."""
    if _connection is None:
        return 'not connected'
    try:
        os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
        _connection.receiver.start_recording(path, float(scene_frame))
    except (skinstream.Error, OSError, ValueError) as e:
        return str(e)
    _connection.record_start = scene_frame
    return None


def stop_recording():
    """Closes the point cache and plays it on a copy of the body (Mesh Cache modifier), starting
    at the scene frame where the recording started. Returns what happened, in one line."""
    c = _connection
    result = None if c is None else c.receiver.stop_recording()
    if result is None:
        return 'nothing was recording'
    path, samples, error = result
    body = bpy.data.objects.get(c.body) if c.body else None
    if error or samples == 0 or body is None:
        c.last_recording = f'{os.path.basename(path)}: {samples} frames' + (f', stopped: {error}' if error else '')
        return c.last_recording
    scene = bpy.data.scenes.get(c.scene_name)
    playback = bpy.data.objects.new(RECORDING, body.data.copy())
    scene.collection.objects.link(playback)
    playback.scale = body.scale
    cache = playback.modifiers.new('skinstream recording', 'MESH_CACHE')
    cache.cache_format = 'PC2'
    cache.filepath = path
    cache.frame_start = c.record_start
    c.last_recording = f'Recorded {samples} frames to {os.path.basename(path)}: "{playback.name}" plays them from frame {c.record_start}'
    return c.last_recording


def _redraw():
    for window in bpy.context.window_manager.windows:
        for area in window.screen.areas:
            if area.type == 'VIEW_3D':
                area.tag_redraw()
