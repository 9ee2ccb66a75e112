"""Warnings about an exported scene that will render black or cannot be solved. No bpy.

Such scenes are valid: the renderers handle them (a black image, the world alone), so the
engine warns and renders instead of failing, as Cycles does.
"""


def emits_light(scene):
    """True when a light (portals only guide sampling), a material or the world of the shgi.Scene
    emits: shgi.bake.emits_light, the one test renders and bakes share."""
    from shgi.bake import emits_light as scene_emits_light  # `scene` is a shgi.Scene: shgi loaded

    return scene_emits_light(scene)


def scene_warnings(scene):
    """Messages for a shgi.Scene without geometry or without anything emitting light."""
    warnings = []
    if scene.empty:
        warnings.append("the scene has no geometry SHGI can render; only the world is visible")
    if not emits_light(scene):
        warnings.append("nothing in the scene emits light (no lights, no emissive materials, "
                        "a black world): the render is black")
    return warnings
