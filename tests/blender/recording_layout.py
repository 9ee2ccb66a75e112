"""Drawing a panel headless: a stand-in for UILayout that records labels and checks props.

Background Blender has no window, so panels never draw; ``draw_panel`` calls a panel class's
draw() with a RecordingLayout instead. Every ``prop(data, name)`` must name an RNA property of
`data` (a typo raises AttributeError, as Blender would print it), every ``operator(idname)`` a
registered operator; label texts are returned for the caller's checks.
"""

import bpy


class _OperatorProperties:
    """What layout.operator() returns: accepts property assignments."""


class RecordingLayout:
    def __init__(self, labels):
        self.labels = labels

    def label(self, text="", icon="NONE"):
        self.labels.append(text)

    def prop(self, data, name, **_kwargs):
        if name not in data.bl_rna.properties:
            raise AttributeError(f"layout.prop: {type(data).__name__} has no property {name!r}")

    def operator(self, idname, **_kwargs):
        module, name = idname.split(".")
        try:
            getattr(getattr(bpy.ops, module), name).get_rna_type()
        except (AttributeError, KeyError):
            raise AttributeError(f"layout.operator: {idname} is not registered") from None
        return _OperatorProperties()

    def separator(self, **_kwargs):
        pass

    def _child(self, *_args, **_kwargs):
        return RecordingLayout(self.labels)

    box = column = row = grid_flow = split = _child


def draw_panel(panel_name, context=None):
    """The label texts bpy.types.<panel_name>.draw() produces, joined by ' | '."""
    labels = []
    cls = getattr(bpy.types, panel_name)
    # A plain object carrying the class's own attributes (helpers, tables) and the layout.
    members = {name: value for name, value in vars(cls).items() if not name.startswith("__")}
    panel = type("Panel", (), dict(members, layout=RecordingLayout(labels)))()
    cls.draw(panel, context or bpy.context)
    return " | ".join(labels)
