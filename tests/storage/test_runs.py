import pyarrow as pa
import pytest

from simsplat_core.eval.grounding.tables import ABLATION_SPEC, GROUNDING_SPEC
from storage import ArtifactStore
from storage.errors import SchemaError
from storage.runs import RunTable, new_run_id, run_dir, write_run_tables


def grounding_table_schema(first):
    return (GROUNDING_SPEC if first == "method" else ABLATION_SPEC).schema


def _table(first="method"):
    row = {first: "ours", **{f"{c}_{m}": 0.5 for c in ("vehicle", "pedestrian", "total") for m in ("acc", "viou")},
           **{f"{c}_queries": 3 for c in ("vehicle", "pedestrian", "total")}}
    return pa.Table.from_pylist([row], schema=grounding_table_schema(first))


def test_tables_land_as_parquet_and_markdown_with_a_manifest(tmp_path):
    store = ArtifactStore(tmp_path)
    rel = run_dir(new_run_id("test"))
    uris = write_run_tables(store, rel, {"grounding": RunTable(_table(), grounding_table_schema("method"), "| a |")},
                            {"queries": 3})
    assert uris["grounding"].endswith(f"{rel}/tables/grounding.parquet")
    back = store.read_table(f"{rel}/tables/grounding.parquet", grounding_table_schema("method"))
    assert back.column("total_acc").to_pylist() == [0.5]
    assert store.read_bytes(f"{rel}/tables/grounding.md") == b"| a |\n"
    manifest = store.read_json(f"{rel}/manifest.json")
    assert manifest["tables"] == ["grounding"] and manifest["queries"] == 3


def test_a_table_that_does_not_match_its_schema_is_refused_naming_the_file(tmp_path):
    store = ArtifactStore(tmp_path)
    with pytest.raises(SchemaError, match="grounding.parquet"):
        write_run_tables(store, "", {"grounding": RunTable(_table("features"), grounding_table_schema("method"), "")})
    assert not store.exists("tables/grounding.parquet")


@pytest.mark.parametrize("bad", ["", "../x", "a/b", "x" * 200])
def test_unsafe_run_ids_are_named(bad):
    with pytest.raises(ValueError, match="run id"):
        run_dir(bad)
