"""Draws the newest viewport frame with the gpu module (bpy side, inside view_draw).

A frame (viewport_worker.Frame: linear RGBA, premultiplied, row 0 at the bottom) is uploaded
once as a half-float texture and drawn over the whole region, whatever its resolution (the
reduced-resolution frames are stretched). Colour management: between
``RenderEngine.bind_display_space_shader(scene)`` and ``unbind_display_space_shader()``, as the
API asks; on Blender 3.x and 4.x the viewport then applies the scene's view transform to what
the engine drew, so the texture holds scene-linear values.

Builtin shader names changed: Blender 4.0 dropped the "2D_" and "3D_" prefixes (3.4 has both,
the prefixed ones deprecated), so the first name the running Blender knows is used.
"""

import gpu
from gpu_extras.batch import batch_for_shader

IMAGE_SHADER_NAMES = ("IMAGE", "2D_IMAGE")
TEXTURE_FORMAT = "RGBA16F"


def builtin_shader(names):
    """The first builtin shader of `names` this Blender has (ValueError names them all)."""
    for name in names:
        try:
            return gpu.shader.from_builtin(name)
        except ValueError:
            continue
    raise ValueError(f"none of the builtin shaders {names} exists in this Blender")


class FrameDisplay:
    """The texture of the last frame drawn, and the quad it is drawn on."""

    def __init__(self):
        self._texture = None
        self._frame_id = None
        self._quad = None         # (width, height, batch)
        self._shader = None

    @property
    def frame_id(self):
        """The frame_id of the frame in the texture (None before the first draw)."""
        return self._frame_id

    def draw(self, engine, scene, frame, width, height):
        """Draws `frame` over a width x height region (pixel space, as view_draw sets it)."""
        if frame.frame_id != self._frame_id:
            self._upload(frame)
        if self._shader is None:
            self._shader = builtin_shader(IMAGE_SHADER_NAMES)
        if self._quad is None or self._quad[:2] != (width, height):
            self._quad = (width, height, batch_for_shader(
                self._shader, "TRI_FAN",
                {"pos": ((0, 0), (width, 0), (width, height), (0, height)),
                 "texCoord": ((0, 0), (1, 0), (1, 1), (0, 1))}))
        gpu.state.blend_set("ALPHA_PREMULT")
        engine.bind_display_space_shader(scene)
        try:
            self._shader.bind()
            self._shader.uniform_sampler("image", self._texture)
            self._quad[2].draw(self._shader)
        finally:
            engine.unbind_display_space_shader()
            gpu.state.blend_set("NONE")

    def _upload(self, frame):
        height, width = frame.pixels.shape[:2]
        # The Buffer wraps the numpy array's memory (buffer protocol); the texture copies it.
        buffer = gpu.types.Buffer("FLOAT", frame.pixels.size, frame.pixels.reshape(-1))
        self._texture = gpu.types.GPUTexture((width, height), format=TEXTURE_FORMAT,
                                             data=buffer)
        self._frame_id = frame.frame_id

    def free(self):
        self._texture = self._quad = None
