"""The pyarrow schema of every persisted table, defined once per domain (``DESIGN.md``, "Data contracts").

Each schema carries file metadata ``schema_name`` and ``schema_version`` (and, for tables with a
variable array width, the width: ``feature_dim``/``color_dim`` for ``gaussians``, ``dim`` for
``nodes``). ``validate_table`` checks a table against a schema and raises ``SchemaError`` naming the
file and every offending column.

Type decisions:

* Fixed-width arrays are ``FixedSizeList<float32>`` (``K[9]`` and 4x4 transforms row-major in
  ``[16]``). Transforms are float32 too: the world frame is the first ego pose, so translations stay
  within a log's extent (<= a few km), where float32 resolves better than 0.5 mm; rotation entries
  keep ~1e-7 relative precision. Scalars that are measurements (``heading``, ``speed``, ``x``, ``y``)
  are float32; metric ``value`` is float64 (aggregates must not lose digits).
* Time is int64 microseconds; frame indices are int64; scene-graph ``node_id`` is int32 (it is
  also written to the EXR ``id`` channel as float32, exact up to 2**24).
* ``objects.attributes`` is ``map<string, string>`` (native, queryable, keeps insertion order).
* ``map_features.points`` is ``list<FixedSizeList<float32, 3>>`` (one variable-length polyline).
* ``deformations.offsets`` is ``list<FixedSizeList<float32, 3>>`` too: the ``[N_h, 3]`` offsets of one
  non-rigid node's Gaussians at one frame (one file per node, ``node_poses.deform_uri`` points at it).
  The asset bank stores a deformable asset's offsets the same way (``assets.deform_uri``).
* Strings are never null: "absent" is the empty string (``image_uri``, ``deform_uri``,
  ``failure_reason``, ``caption``). Every column is non-nullable, except columns added to a table in a later
  version (e.g. the ``edits`` table's mining columns): they are nullable, and a file of an older version that
  lacks them is read with them all null.

Modules: ``base`` (metadata keys, ``vec``, ``make_schema``, vector columns), ``logs``, ``scenes``, ``language``,
``edits``, ``runs`` (the domains' schemas), ``registry`` (``TABLES``: name -> how to build the schema) and
``validation`` (``validate_table``, ``json_schema``). Evaluation tables are declared with the code that computes
them (``simsplat_core.eval.table_spec``) and validated by the same ``validate_table``.
"""
