"""SHGI: spherical-harmonics global illumination for Blender (the add-on).

This module only describes and registers the add-on; the work lives in its packages (export/
turns Blender scenes into shgi.Scene). It imports without bpy so that bpy-free parts of the
add-on can be tested with pytest.
"""

bl_info = {
    "name": "SHGI",
    "author": "SHGI developers",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Properties > Render > Render Engine",
    "description": "Spherical-harmonics global illumination previews and bakes",
    "category": "Render",
}

# Classes to register, in order (the render engine, properties and panels come in later issues).
_CLASSES = ()


def register():
    """Registers the add-on's classes with Blender."""
    import bpy

    for cls in _CLASSES:
        bpy.utils.register_class(cls)


def unregister():
    """Unregisters the add-on's classes, in reverse order."""
    import bpy

    for cls in reversed(_CLASSES):
        bpy.utils.unregister_class(cls)
