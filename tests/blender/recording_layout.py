"""Drawing a panel headless: a stand-in for UILayout that records labels and checks props.

Background Blender has no window, so panels never draw; ``draw_panel`` calls a panel class's
draw() with a RecordingLayout instead. Every ``prop(data, name)`` must name an RNA property of
`data` (a typo raises AttributeError, as Blender would print it), every ``operator(idname)`` a
registered operator; label texts are returned for the caller's checks. ``draw_panel_rows``
returns the labels per row (each ``row()`` or ``split()`` of the layout), to check what sits
beside what; ``draw_panel_props`` the (data, property name, text) of each ``prop`` drawn,
``draw_panel_operators`` the (operator id, text) of each button. Each takes a panel's name or
a class with a draw() (an add-on's AddonPreferences).
"""

import bpy


class _OperatorProperties:
    """What layout.operator() returns: accepts property assignments."""


class RecordingLayout:
    def __init__(self, labels, rows=None, props=None, row=None, operators=None):
        self.labels = labels
        self.rows = [] if rows is None else rows
        self.props = [] if props is None else props
        self.operators = [] if operators is None else operators
        self._row = row  # the labels of the row() or split() this layout is in, if any

    def label(self, text="", icon="NONE"):
        self.labels.append(text)
        if self._row is not None:
            self._row.append(text)

    def prop(self, data, name, text=None, **_kwargs):
        if name not in data.bl_rna.properties:
            raise AttributeError(f"layout.prop: {type(data).__name__} has no property {name!r}")
        self.props.append((data, name,
                           data.bl_rna.properties[name].name if text is None else text))

    def operator(self, idname, text=None, **_kwargs):
        self.operators.append((idname, _operator_type(idname).name if text is None else text))
        return _OperatorProperties()

    def operator_menu_enum(self, idname, property, text="", **_kwargs):
        if property not in _operator_type(idname).properties:
            raise AttributeError(f"layout.operator_menu_enum: {idname} has no {property!r}")
        self.operators.append((idname, text))

    def separator(self, **_kwargs):
        pass

    def _child(self, *_args, **_kwargs):
        return RecordingLayout(self.labels, self.rows, self.props, self._row, self.operators)

    def _new_row(self, *_args, **_kwargs):
        row = []
        self.rows.append(row)
        return RecordingLayout(self.labels, self.rows, self.props, row, self.operators)

    box = column = grid_flow = _child
    row = split = _new_row


def _operator_type(idname):
    """The RNA type of registered operator `idname`; AttributeError when there is none."""
    module, name = idname.split(".")
    try:
        return getattr(getattr(bpy.ops, module), name).get_rna_type()
    except (AttributeError, KeyError):
        raise AttributeError(f"layout.operator: {idname} is not registered") from None


def _draw(panel_name, context):
    """Draws bpy.types.<panel_name>, or `panel_name` itself when it is a class (an
    AddonPreferences subclass, which bpy.types does not list)."""
    labels = []
    layout = RecordingLayout(labels)
    cls = panel_name if isinstance(panel_name, type) else getattr(bpy.types, panel_name)
    # A plain object carrying the class's own attributes (helpers, tables) and the layout.
    members = {name: value for name, value in vars(cls).items() if not name.startswith("__")}
    panel = type("Panel", (), dict(members, layout=layout))()
    cls.draw(panel, context or bpy.context)
    return layout


def draw_panel(panel_name, context=None):
    """The label texts bpy.types.<panel_name>.draw() produces, joined by ' | '."""
    return " | ".join(_draw(panel_name, context).labels)


def draw_panel_rows(panel_name, context=None):
    """The label texts of each row (row() or split()) the panel draws, as tuples."""
    return [tuple(row) for row in _draw(panel_name, context).rows if row]


def draw_panel_props(panel_name, context=None):
    """(data, property name, the text shown for it) of each prop() the panel draws."""
    return _draw(panel_name, context).props


def draw_panel_operators(panel_name, context=None):
    """(operator id, the button's text) of each operator() button the panel draws."""
    return _draw(panel_name, context).operators
