"""Blender lights and the world → shgi.Light and shgi.World (bpy side; units in conversions.py).

Lights keep Blender's units (W, W/m²; an area light's power in Blender 3.4's) and frame
(matrix_world, emitting along local -Z). The world is uniform: the Background node's Color ×
Strength, or World.color without nodes. A textured world colour is replaced by the image's
solid-angle weighted average, with a warning.
"""

import bpy
import shgi

from . import conversions, node_tree
from .material import image_pixels

WORLD_OUTPUT_NODE = "ShaderNodeOutputWorld"
BACKGROUND_NODE = "ShaderNodeBackground"
ENVIRONMENT_TEXTURE_NODES = ("ShaderNodeTexEnvironment", "ShaderNodeTexImage")
# What Cycles renders when the scene has no world, or nothing drives its World Output: black.
NO_WORLD_COLOR = (0.0, 0.0, 0.0)


def light_from_object(obj, matrix_world, log=None):
    """shgi.Light of an evaluated light object placed at `matrix_world` (ValueError if invalid);
    settings SHGI does not render are named in a warning on `log`."""
    data = obj.data
    ignored = conversions.ignored_light_settings(
        {name: getattr(data, name) for name in conversions.IGNORED_LIGHT_SETTINGS
         if hasattr(data, name)})
    if ignored and log is not None:
        log.warn(f"light {obj.name!r}: {', '.join(ignored)} not rendered by SHGI and ignored")
    fields = conversions.light_fields(
        data.type, data.energy, data.color, matrix_world,
        shadow_soft_size=getattr(data, "shadow_soft_size", 0.0),
        spot_size=getattr(data, "spot_size", 0.0), spot_blend=getattr(data, "spot_blend", 0.0),
        angle=getattr(data, "angle", 0.0), shape=getattr(data, "shape", "SQUARE"),
        size=getattr(data, "size", 0.0), size_y=getattr(data, "size_y", 0.0),
        visible_camera=getattr(obj, "visible_camera", False),
        portal=getattr(getattr(data, "cycles", None), "is_portal", False), name=obj.name,
        blender_version=bpy.app.version, exposure=getattr(data, "exposure", 0.0))
    return shgi.Light(**fields)


def world_from_blender(world, log):
    """shgi.World of a Blender World (None = no world: black)."""
    if world is None:
        return shgi.World(**conversions.world_fields(NO_WORLD_COLOR, 1.0))
    if not world.use_nodes or world.node_tree is None:
        return shgi.World(**conversions.world_fields(world.color, 1.0))
    output = node_tree.active_output(world.node_tree, WORLD_OUTPUT_NODE)
    surface = node_tree.linked_node(output.inputs["Surface"]) if output else None
    if surface is None:
        return shgi.World(**conversions.world_fields(NO_WORLD_COLOR, 1.0))
    if surface.bl_idname != BACKGROUND_NODE:
        log.warn(f"world {world.name!r}: surface shader {surface.bl_idname} is not a Background; "
                 "using World.color with strength 1")
        return shgi.World(**conversions.world_fields(world.color, 1.0))
    values = node_tree.input_values(surface)
    color = _background_color(world, surface, values["Color"], log)
    if surface.inputs["Strength"].is_linked:
        log.warn(f"world {world.name!r}: Background Strength is driven by a node; its unlinked "
                 "value is used")
    return shgi.World(**conversions.world_fields(color, values["Strength"]))


def _background_color(world, background, unlinked_color, log):
    """The Background's colour: its value, or the average of an environment image."""
    source = node_tree.linked_node(background.inputs["Color"])
    if source is None:
        return unlinked_color
    image = getattr(source, "image", None)
    if source.bl_idname in ENVIRONMENT_TEXTURE_NODES and image is not None and all(image.size):
        color = conversions.equirect_average(image_pixels(image, log))
        log.warn(f"world {world.name!r}: textured worlds are uniform in SHGI; using the average "
                 f"colour {tuple(round(c, 4) for c in color)} of image {image.name!r}")
        return color
    log.warn(f"world {world.name!r}: Background Color is driven by a {source.bl_idname} node; "
             "its unlinked value is used")
    return unlinked_color
