"""Long messages in panels, wrapped to the region's width (Blender's labels do not wrap)."""

import textwrap

import bpy

# Long messages are wrapped to the Properties editor's width: the UI font averages about 5.1 px
# a character at 11 pt and scale 1 in these sentences (blf), and a label loses about 50 px to the
# panel's margins and its icon. The default editor is 303 px wide (factory startup, 1920 x
# 1080 window): 46 characters, used when there is no region (scripts, headless tests).
CHAR_PIXELS = 5.5
MARGIN_PIXELS = 50
DEFAULT_REGION_PIXELS = 303
MIN_WRAP_COLUMNS = 20


def wrap_columns(region_width=None, ui_scale=1.0):
    """Characters per line of a wrapped message in a region `region_width` px wide."""
    width = region_width if region_width and region_width > 1 else DEFAULT_REGION_PIXELS
    return max(MIN_WRAP_COLUMNS, int((width - MARGIN_PIXELS * ui_scale) / (CHAR_PIXELS * ui_scale)))


def draw_wrapped(layout, text, icon="NONE"):
    """Draws `text` as several labels (Blender's labels do not wrap) that fit the region."""
    region = getattr(bpy.context, "region", None)
    # The effective scale (resolution scale x DPI); background Blender has none (0).
    columns = wrap_columns(getattr(region, "width", None),
                           bpy.context.preferences.system.ui_scale or 1.0)
    column = layout.column(align=True)
    for index, line in enumerate(textwrap.wrap(text, columns)):
        column.label(text=line, icon=icon if index == 0 else "BLANK1")
