"""Warnings about an exported scene that will render black or cannot be solved. No bpy.

Such scenes are valid: the renderers handle them (a black image, the world alone), so the
engine warns and renders instead of failing, as Cycles does.
"""


def emits_light(scene):
    """True when a light (portals only guide sampling), a material or the world emits."""
    if any(not light.portal for light in scene.lights):
        return True
    if any(material.is_emissive() for material in scene.materials):
        return True
    world = scene.world
    return world.strength > 0.0 and max(world.color) > 0.0


def scene_warnings(scene):
    """Messages for a shgi.Scene without geometry or without anything emitting light."""
    warnings = []
    if scene.empty:
        warnings.append("the scene has no geometry SHGI can render; only the world is visible")
    if not emits_light(scene):
        warnings.append("nothing in the scene emits light (no lights, no emissive materials, "
                        "a black world): the render is black")
    return warnings
