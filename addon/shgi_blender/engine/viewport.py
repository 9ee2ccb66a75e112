"""The live viewport (Rendered shading) of the SHGI engine: bpy side, Blender's main thread.

One ViewportSession per viewport engine instance:
* ``view_update`` syncs the scene (viewport_sync.ViewportSync: only what changed is exported)
  and sends the snapshot with the render properties to the worker;
* ``view_draw`` reads the view from the region (viewport_camera), sends it to the worker (the
  worker ignores a request equal to the current one, and cancels the running call otherwise),
  then draws the newest frame (frame_display) and shows the worker's status in the header;
* the worker (viewport_worker, a thread that never touches bpy) builds, commits, solves and
  renders, and leaves frames in a lock-protected slot.

A worker thread must not call ``RenderEngine.tag_redraw``; one ``bpy.app.timers`` timer on the
main thread polls every session for a new frame and tags the Rendered 3D views for redraw.
Sessions end with their engine (``__del__``), when a file loads and when the add-on unregisters.
"""

import bpy

from .. import native, settings
from .frame_display import FrameDisplay
from .viewport_camera import camera_fields_from_view

REDRAW_POLL_SECONDS = 0.05

_sessions = set()


class ViewportSession:
    """The sync, the worker and the display of one viewport."""

    def __init__(self):
        # Imported here: they import shgi, and this module must load without it (the engine
        # registers and explains the import error).
        from .viewport_sync import ViewportSync
        from .viewport_worker import ViewportWorker

        self.sync = ViewportSync()
        self.worker = ViewportWorker(native.module())
        self.display = FrameDisplay()
        self.scene_key = None
        self.properties = None
        self.view = None
        self.drawn_status = None
        _sessions.add(self)
        if not bpy.app.timers.is_registered(_poll_sessions):
            bpy.app.timers.register(_poll_sessions, first_interval=REDRAW_POLL_SECONDS)

    def view_update(self, _engine, _context, depsgraph):
        scene = depsgraph.scene
        self.scene_key = scene.name_full
        self.sync.sync(depsgraph)
        self.properties = settings.render_property_values(scene.shgi)
        self.worker.set_overlay_wanted(settings.overlay_wanted(scene.shgi))
        self._request()

    def view_draw(self, engine, context, depsgraph):
        region, region_data = context.region, context.region_data
        self.view = camera_fields_from_view(region_data.view_matrix, region_data.window_matrix,
                                            region.width, region.height)
        self._request()
        frame = self.worker.latest_frame()
        if frame is not None:
            self.display.draw(engine, depsgraph.scene, frame, region.width, region.height)
        self.drawn_status = self.worker.status
        engine.update_stats("", f"SHGI | {self.drawn_status}")

    @property
    def drawn_frame_id(self):
        """The frame_id of the frame drawn last (None before the first draw)."""
        return self.display.frame_id

    def _request(self):
        if self.view is not None and self.sync.snapshot is not None:
            self.worker.request(self.sync.snapshot, self.view, self.properties)

    def needs_redraw(self):
        frame = self.worker.latest_frame()
        return ((frame is not None and frame.frame_id != self.drawn_frame_id)
                or self.worker.status != self.drawn_status)

    def stop(self):
        self.worker.stop()
        self.display.free()
        _sessions.discard(self)


def sessions():
    """The running sessions (the overlay and the tests read them)."""
    return list(_sessions)


def stop_all():
    for session in list(_sessions):
        session.stop()


def _poll_sessions():
    """Timer: tags the Rendered 3D views for redraw when a session has a frame or a status not
    drawn yet."""
    if not _sessions:
        return None
    if any(session.needs_redraw() for session in _sessions):
        for window in bpy.context.window_manager.windows:
            for area in window.screen.areas:
                if area.type == "VIEW_3D" and area.spaces.active.shading.type == "RENDERED":
                    area.tag_redraw()
    return REDRAW_POLL_SECONDS
