"""The panel's settings, kept in the scene (saved with the .blend file)."""
import bpy

from . import live


class SkinstreamSettings(bpy.types.PropertyGroup):
    host: bpy.props.StringProperty(name='Host', default='127.0.0.1', description="The daemon's address")
    port: bpy.props.IntProperty(name='Port', default=8481, min=1, max=65535, description="The daemon's subscriber port")
    subject: bpy.props.StringProperty(name='Subject', default='', description="The capture system's name of the subject (empty: the daemon's first)")
    encoding: bpy.props.EnumProperty(
        name='Encoding',
        items=[('parameters', 'Parameters', 'About 8 kB a frame; evaluated here (numpy)'),
               ('compressed', 'Compressed', 'About 120 kB a frame; decoded here (numpy)'),
               ('quantised', 'Quantised', '16-bit positions, about 320 kB a frame'),
               ('float', 'Float', '32-bit positions, about 640 kB a frame')],
        default='compressed')
    token: bpy.props.StringProperty(name='Token', default='', subtype='PASSWORD', description="The daemon's shared token, when it has one")
    show_markers: bpy.props.BoolProperty(name='Markers', default=False, description='Show the filled markers as a point cloud',
                                         update=lambda self, context: live.show_markers(self.show_markers))
    scale: bpy.props.FloatProperty(name='Scale', default=0.001, min=1e-6, description='Object scale: the stream is in mm (0.001 shows it in metres)')
    record_path: bpy.props.StringProperty(name='Record to', default='//skinstream.pc2', subtype='FILE_PATH',
                                          description='PC2 point cache the recording writes')
