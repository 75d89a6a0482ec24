"""Language-controlled scene editing: the command schema, the parser, the asset bank, placement, the motion
controller and ``apply_edit`` (by value: the stored scene is never changed)."""
