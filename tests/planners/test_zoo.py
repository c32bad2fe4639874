"""The model zoo: its index against the shipped files (sha256 by hashlib), zoo names as `--weights`, the checksum
check on load (one line, exit 2), the packaged index of the committed bench entries, and `vinadv planners --json`."""

import hashlib
import json
import shutil
from pathlib import Path

import pytest

from vinadv.bench.index import SHIPPED_INDEX, index_json, make_index, read_index
from vinadv.bench.leaderboard import read_entries
from vinadv.bench.scoring import entry_key, spec_key
from vinadv.bench.suites import get_suite
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.planners import zoo
from vinadv.planners.registry import PlannerRef, load_planner
from vinadv.planners.registry import models as zoo_models
from vinadv.planners.weights import WEIGHTS_DIR

ROOT = Path(__file__).resolve().parents[2]
ENTRIES = ROOT / "docs" / "results" / "bench"


def sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def test_the_zoo_names_every_shipped_weights_file_with_its_sha256_and_files():
    models = zoo.read_zoo()
    assert sorted(m.file for m in models.values()) == sorted(p.name for p in WEIGHTS_DIR.glob("*.pt"))
    for m in models.values():
        assert m.sha256 == sha256(m.path), m.name
        for name in (m.record, m.metrics, m.licence_file):
            assert name is None or (WEIGHTS_DIR / name).is_file(), name
        zoo.verify(m.path)  # the shipped files pass their own check
        assert m.to_dict()["training"]["format"].startswith("vinadv.")


def test_a_zoo_name_loads_its_weights_and_wrong_kinds_are_refused():
    robust = load_planner("vin", 28, weights="vin28-robust")
    assert robust.checksum == sha256(WEIGHTS_DIR / "vin28_robust.pt") == load_planner("vin-robust", 28).checksum
    with pytest.raises(InputError, match="holds vin weights .* not gppn weights"):
        load_planner("gppn", 28, weights="vin28")
    ref = PlannerRef.of(robust, "vin", "vin28-robust", True)  # one planner, one reference
    assert (ref.spec, ref.weights) == ("vin-robust", None) and ref.load().checksum == robust.checksum


@pytest.fixture
def tampered_zoo(tmp_path, monkeypatch):
    """A copy of the weights folder whose vin28.pt has one byte changed; the zoo reads that folder."""
    folder = tmp_path / "weights"
    folder.mkdir()
    for name in ("vin28.pt", "vin28.json"):
        shutil.copy(WEIGHTS_DIR / name, folder / name)
    data = bytearray((folder / "vin28.pt").read_bytes())
    data[-100] ^= 1
    (folder / "vin28.pt").write_bytes(bytes(data))
    monkeypatch.setattr(zoo_models, "WEIGHTS_DIR", folder)
    return folder / "vin28.pt"


def test_a_changed_zoo_file_is_refused_naming_it_and_both_checksums(tampered_zoo, tmp_path, capsys):
    shipped = sha256(WEIGHTS_DIR / "vin28.pt")
    with pytest.raises(InputError) as err:
        zoo.verify(tampered_zoo)
    assert str(tampered_zoo) in str(err.value) and shipped in str(err.value) and sha256(tampered_zoo) in str(err.value)
    out = tmp_path / "e.json"
    argv = ["bench", "run", "--suite", "vin28-quick-v1", "--weights", "vin28", "--out", str(out), "--quiet"]
    assert main(argv) == 2  # refused when the planner loads, before any map is made
    err_text = capsys.readouterr().err.strip()
    assert len(err_text.splitlines()) == 1 and shipped in err_text and sha256(tampered_zoo) in err_text
    assert not out.exists()


def test_the_shipped_bench_index_is_the_committed_entries():
    expected = index_json(make_index(read_entries(ENTRIES), "docs/results/bench"))
    assert SHIPPED_INDEX.read_text(encoding="utf-8") == expected, (
        "regenerate: vinadv bench leaderboard docs/results/bench --out OUT --index src/vinadv/bench/entries.json"
    )


def test_planners_json_lists_weights_licence_training_and_bench_entries(capsys):
    assert main(["planners", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    by_name = {p["name"]: p for p in out["planners"]}
    assert by_name["vin"]["zoo"] == "vin28" and by_name["vin"]["weights_sha256"] == sha256(WEIGHTS_DIR / "vin28.pt")
    assert by_name["vin-robust"]["training"]["command"].startswith("vinadv vin train")
    assert "OMRON" in by_name["neural-astar"]["licence"] and by_name["optimal"]["weights_sha256"] is None
    rows = read_index()
    for p in out["planners"]:
        for e in p["bench_entries"]:  # each listed entry is a committed file of that planner and weights
            assert e in rows and sha256(ROOT / e["file"]) == e["sha256"]
            assert e["planner"]["name"] == p["name"] and e["weights_sha256"] == p["weights_sha256"]
    assert {e["suite"] for e in by_name["optimal"]["bench_entries"]} >= {"vin28-quick-v1"}
    assert {m["name"] for m in out["zoo"]} == set(zoo.read_zoo())


def test_zoo_names_are_hyphenated_and_the_old_ones_still_name_their_model():
    old = {
        "vin28_robust": "vin28-robust",
        "vin_mpd32": "vin-mpd32",
        "gppn_mpd32": "gppn-mpd32",
        "neural_astar_mazes32": "neural-astar-mazes32",
        "neural_astar_mpd5": "neural-astar-mpd5",
    }
    assert all("_" not in name for name in zoo.read_zoo())
    for alias, name in old.items():
        assert zoo.zoo_model(alias) is zoo.zoo_model(name) is not None, alias
        assert zoo.resolve(alias, zoo.zoo_model(name).kind) == str(WEIGHTS_DIR / zoo.zoo_model(name).file)
    # each model's loader is its planner's, as "module:function"
    assert zoo.zoo_model("vin28-robust").loader == "vinadv.planners.registry.loaders:load_vin"


def test_every_committed_entry_keeps_its_key_read_in_todays_spelling():
    """The key of each committed entry, from its spec as stored, is the key of its spec as read (upgraded to today's
    names): `--resume` finds the chunks a database holds for it."""
    upgraded = dict(read_entries(ENTRIES))
    renamed = 0
    for path in sorted(ENTRIES.glob("*.json")):
        stored = json.loads(path.read_text())
        read = upgraded[path]
        assert "_" not in read["planner"]["name"], path.name
        renamed += read["planner"]["name"] != stored["planner"]["name"]
        # chunks key by the name as first stored: `vin_robust`, also for entries stored since as `vin-robust`
        first = {
            **stored["planner"],
            "name": "vin_robust" if read["planner"]["name"] == "vin-robust" else stored["planner"]["name"],
        }
        raw = hashlib.sha256(json.dumps([stored["suite"]["checksum"], first], sort_keys=True).encode())
        assert spec_key(read["suite"]["checksum"], read["planner"]) == raw.hexdigest(), path.name
    assert renamed == 2  # vin28-v1 and vin28-quick-v1 of vin_robust, now vin-robust


@pytest.mark.parametrize(
    "choice",
    [("vin_robust", None), ("vin-robust", None), ("vin", "vin28_robust"), ("vin", "vin28-robust")],
    ids=str,
)
def test_old_and_new_spellings_give_the_committed_entrys_key(choice):
    stored = json.loads((ENTRIES / "vin28-quick-v1.vin_robust.json").read_text())
    suite = get_suite("vin28-quick-v1")
    planner = load_planner(choice[0], 28, weights=choice[1])
    assert planner.name == "vin-robust"
    raw = hashlib.sha256(json.dumps([suite.checksum, stored["planner"]], sort_keys=True).encode()).hexdigest()
    assert entry_key(suite, planner) == raw
