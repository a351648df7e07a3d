"""skinstream live: a skinstreamd's subject as a Blender mesh that deforms as the capture plays,
its markers as an optional point cloud, and a recording to a PC2 point cache that Blender's Mesh
Cache modifier plays back. The socket is read on a background thread (skinstream.Receiver, the
Python package, vendored in the add-on's zip); a timer on Blender's thread applies the newest
frame at each tick and never waits for the network."""

bl_info = {
    'name': 'skinstream live',
    'author': 'skinstream',
    'version': (0, 1, 0),
    'blender': (3, 4, 0),
    'location': 'View3D > Sidebar > skinstream',
    'description': "Streams a skinstreamd subject's deforming body mesh and markers into the scene",
    'category': 'Animation',
}

if 'bpy' in locals():  # F8 / reload scripts
    import importlib
    from . import live, operators, panel, properties
    for module in (live, properties, operators, panel):
        importlib.reload(module)
else:
    from . import live, operators, panel, properties

import bpy  # noqa: E402

_classes = (properties.SkinstreamSettings, operators.Connect, operators.Disconnect, operators.StartRecording,
            operators.StopRecording, panel.SkinstreamPanel)


def register():
    for cls in _classes:
        bpy.utils.register_class(cls)
    bpy.types.Scene.skinstream = bpy.props.PointerProperty(type=properties.SkinstreamSettings)


def unregister():
    live.disconnect()
    del bpy.types.Scene.skinstream
    for cls in reversed(_classes):
        bpy.utils.unregister_class(cls)
