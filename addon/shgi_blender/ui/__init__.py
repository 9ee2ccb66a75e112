"""Panels: render settings (render_panels.py), light and view-layer passes (data_panels.py),
the stock Blender panels shown under SHGI as under Cycles (compat.py), the field overlay
of the 3D views (field_overlay.py: lattice samples or probes), and the (label, value) rows of
the figures panels show (figure_rows.py, bpy-free)."""


def register():
    import bpy

    from . import compat, data_panels, field_overlay, render_panels

    for cls in render_panels.CLASSES + data_panels.CLASSES:
        bpy.utils.register_class(cls)
    compat.add_engine_to_stock_panels()
    field_overlay.register()


def unregister():
    import bpy

    from . import compat, data_panels, field_overlay, render_panels

    field_overlay.unregister()
    compat.remove_engine_from_stock_panels()
    for cls in reversed(render_panels.CLASSES + data_panels.CLASSES):
        bpy.utils.unregister_class(cls)
