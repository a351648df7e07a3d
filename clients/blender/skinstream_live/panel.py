"""The sidebar panel: where to connect, what the connection is doing, recording."""
import bpy

from . import live


class SkinstreamPanel(bpy.types.Panel):
    bl_idname = 'VIEW3D_PT_skinstream'
    bl_label = 'skinstream'
    bl_space_type = 'VIEW_3D'
    bl_region_type = 'UI'
    bl_category = 'skinstream'

    def draw(self, context):
        s = context.scene.skinstream
        layout = self.layout
        column = layout.column()
        column.enabled = not live.connected()
        column.prop(s, 'host')
        column.prop(s, 'port')
        column.prop(s, 'subject')
        column.prop(s, 'encoding')
        column.prop(s, 'token')
        if live.connected():
            layout.operator('skinstream.disconnect', icon='CANCEL')
        else:
            layout.operator('skinstream.connect', icon='PLAY')
        box = layout.box()
        for line in live.status_lines():
            box.label(text=line)
        layout.prop(s, 'show_markers')
        layout.prop(s, 'record_path')
        if live.recording() is None:
            layout.operator('skinstream.start_recording', icon='REC')
        else:
            layout.operator('skinstream.stop_recording', icon='SNAP_FACE')
