"""Scenarios in the formats planners train on: one format-neutral record (``record.ExportScenario``), built from
a stored log or edit (``from_log``), written as Waymo Open Motion ``Scenario`` shards, ScenarioNet pickles or a
Parquet dataset of the project's own."""
