"""SHGI: spherical-harmonics global illumination for Blender (the add-on).

This module only describes and registers the add-on; the work lives in its packages:
properties.py (scene.shgi; versioning.py brings files saved with older settings up to date),
engine/ (the SHGI render engine, F12), operators/ (quality presets, frozen lattice solutions,
lightmap bakes, volume export), ui/ (panels), export/ (Blender scenes → shgi.Scene),
preferences.py (Documentation and Report a Bug; help.py without bpy). It imports
without bpy so that the bpy-free parts can be tested with pytest, and registers even when the
native module ``shgi`` cannot be imported (the render panel then shows why and the fix).
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

# Registered in this order, unregistered in reverse: properties (and their versioning of older
# files) before the engine and the panels that read them.
_PACKAGES = ("properties", "versioning", "engine", "operators", "ui", "preferences")


def _modules():
    import importlib

    return [importlib.import_module(f"{__name__}.{name}") for name in _PACKAGES]


def register():
    """Registers the add-on's properties, render engine, operators and panels."""
    for module in _modules():
        module.register()


def unregister():
    """Unregisters everything register() registered, in reverse order."""
    for module in reversed(_modules()):
        module.unregister()
