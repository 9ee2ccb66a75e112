"""Operators: quality presets (quality_preset.py), solve and clear a frozen solution of the
method's field (frozen_solution.py), bake lightmaps and merge their shards (bake_lightmaps.py,
with lightmap_images.py turning results into images and material nodes), export the solved
field as a volume (export_volume.py)."""


def _classes():
    from . import bake_lightmaps, export_volume, frozen_solution, quality_preset

    return (quality_preset.CLASSES + frozen_solution.CLASSES + bake_lightmaps.CLASSES
            + export_volume.CLASSES)


def register():
    import bpy

    from . import lightmap_images

    for cls in _classes():
        bpy.utils.register_class(cls)
    lightmap_images.register()


def unregister():
    import bpy

    from . import lightmap_images

    lightmap_images.unregister()
    for cls in reversed(_classes()):
        bpy.utils.unregister_class(cls)
