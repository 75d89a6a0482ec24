"""Language-controlled scene editing: the command schema, the parser, the asset bank, placement, the motion
controller and ``apply_edit`` (by value: the stored scene is never changed).

Top level: ``commands`` (the ``EditCommand`` schema), ``apply`` (``apply_edit``, ``Editor``), ``draft``
(``EditContext``, ``Draft``), ``ops`` (the four edit ops), ``options``, ``result``, ``delta``, ``grounding``
and ``renders``. Subpackages: ``parse`` (prompt -> program), ``behaviours`` (one declaration per motion
behaviour), ``assets`` (the asset bank), ``placement`` (the placement resolver), ``motion`` (the motion
controller) and ``traffic`` (the traffic's reaction and the room search)."""
