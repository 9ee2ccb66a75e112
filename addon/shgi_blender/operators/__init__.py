"""Operators: quality presets (quality_preset.py), solve and clear a frozen solution of the
method's field (frozen_solution.py)."""


def register():
    import bpy

    from . import frozen_solution, quality_preset

    for cls in quality_preset.CLASSES + frozen_solution.CLASSES:
        bpy.utils.register_class(cls)


def unregister():
    import bpy

    from . import frozen_solution, quality_preset

    for cls in reversed(quality_preset.CLASSES + frozen_solution.CLASSES):
        bpy.utils.unregister_class(cls)
