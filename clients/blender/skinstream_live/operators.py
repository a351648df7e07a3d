"""Connect, disconnect, record."""
import bpy

from . import live


class Connect(bpy.types.Operator):
    bl_idname = 'skinstream.connect'
    bl_label = 'Connect'
    bl_description = 'Subscribe to the daemon (reconnects by itself when it goes away)'

    def execute(self, context):
        s = context.scene.skinstream
        live.connect(context.scene, s.host, s.port, s.encoding, s.subject, s.token)
        return {'FINISHED'}


class Disconnect(bpy.types.Operator):
    bl_idname = 'skinstream.disconnect'
    bl_label = 'Disconnect'

    def execute(self, context):
        live.disconnect()
        return {'FINISHED'}


class StartRecording(bpy.types.Operator):
    bl_idname = 'skinstream.start_recording'
    bl_label = 'Record'
    bl_description = 'Record every frame that arrives to the PC2 point cache'

    @classmethod
    def poll(cls, context):
        return live.can_record()

    def execute(self, context):
        error = live.start_recording(bpy.path.abspath(context.scene.skinstream.record_path), context.scene.frame_current)
        if error:
            self.report({'ERROR'}, error)
            return {'CANCELLED'}
        return {'FINISHED'}


class StopRecording(bpy.types.Operator):
    bl_idname = 'skinstream.stop_recording'
    bl_label = 'Stop recording'
    bl_description = 'Close the point cache and play it back on the body with a Mesh Cache modifier'

    @classmethod
    def poll(cls, context):
        return live.recording() is not None

    def execute(self, context):
        message = live.stop_recording()
        self.report({'INFO'}, message)
        return {'FINISHED'}
