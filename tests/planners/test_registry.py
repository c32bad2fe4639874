"""The planner registry, bring-your-own specs, the shipped example, and the CLI (`vinadv planners`, `plan`)."""

import importlib.util
import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import torch

from tests.planner_files import NO_PARAMETERS
from vinadv.cli import main
from vinadv.errors import InputError
from vinadv.grid import MapSet, generate_maps
from vinadv.planners import registry
from vinadv.planners.classical.astar import WeightedAStarPlanner
from vinadv.planners.classical.optimal import OptimalPlanner
from vinadv.planners.interface import PlannerError
from vinadv.planners.pathset import PathSet
from vinadv.planners.registry import list_planners, load_planner
from vinadv.planners.rollout import rollout_logits
from vinadv.planners.vin.weights import default_weights_path

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "my_planner.py"

#: the registered planners, in the order `vinadv planners` lists them
REGISTERED = [
    "vin",
    "vin-robust",
    "gppn",
    "vin-mpd32",
    "gppn-mpd32",
    "optimal",
    "astar",
    "wastar",
    "neural-astar",
    "neural-astar-mpd5",
    "transpath-cf",
    "transpath-focal",
]


def test_list_names_the_registered_planners():
    names = [p["name"] for p in list_planners(28)]
    assert names == REGISTERED
    vin = list_planners(28)[0]
    assert vin["weights"].endswith("vin28.pt") and vin["weights_available"] is True


def test_unknown_names_and_bad_specs_are_refused():
    with pytest.raises(PlannerError, match="unknown planner 'vim'"):
        load_planner("vim", 28)
    with pytest.raises(PlannerError, match="no such file"):
        load_planner("nowhere/x.py:make", 28)
    with pytest.raises(PlannerError, match="has no callable 'nothere'"):
        load_planner(f"{EXAMPLE}:nothere", 28)
    with pytest.raises(PlannerError, match="cannot import module"):
        load_planner("no_such_module_xyz:make", 28)
    with pytest.raises(PlannerError, match="takes no weights file"):
        load_planner("optimal", 28, weights="w.pt")
    with pytest.raises(InputError, match="no shipped GPPN weights for 12x12"):
        load_planner("gppn", 12)


def test_module_factory_spec(tmp_path, monkeypatch):
    (tmp_path / "userpkg_planner.py").write_text(EXAMPLE.read_text())
    monkeypatch.syspath_prepend(str(tmp_path))
    planner = load_planner("userpkg_planner:make", 16)
    maps = generate_maps(3, 16, seed=1, n_starts=2)
    result = planner.plan(maps.obstacles, maps.starts, maps.goals)
    assert len(result) == 6
    spec = planner.spec()
    assert spec["name"] == "userpkg_planner:make" and spec["config"]["factory"] == "make"
    assert len(spec["weights_sha256"]) == 64 and len(spec["config"]["source_sha256"]) == 64


def test_factory_returning_something_else_is_refused(tmp_path):
    (tmp_path / "p.py").write_text("def make(size):\n    return 'not a module'\n")
    with pytest.raises(PlannerError, match=r"make\(28\) returned str, expected a torch.nn.Module"):
        load_planner(f"{tmp_path / 'p.py'}:make", 28)


def test_the_shipped_example_plans_from_the_cli(tmp_path, capsys):
    maps_file, out = tmp_path / "m.npz", tmp_path / "p.npz"
    assert (
        main(["maps", "generate", "--n", "4", "--size", "12", "--seed", "3", "--out", str(maps_file), "--quiet"]) == 0
    )
    capsys.readouterr()  # the maps' summary
    assert main(["plan", "--maps", str(maps_file), "--out", str(out), "--planner", f"{EXAMPLE}:make", "--json"]) == 0
    summary = json.loads(capsys.readouterr().out)
    assert summary["planner"]["name"].endswith("my_planner.py:make") and summary["paths"] == 4 * 7
    paths = PathSet.load(out)
    assert paths.model.startswith(str(EXAMPLE)) and "sha256=" in paths.model
    # the same paths as planning through the library
    spec = importlib.util.spec_from_file_location("example_planner", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    net = module.make(12).eval()
    m = MapSet.load(maps_file)
    with torch.no_grad():
        logits = net(torch.from_numpy(m.obstacles.astype(np.float32)), torch.from_numpy(m.goals)).numpy()
    want = rollout_logits(logits, m.obstacles, m.goals, m.starts, m.corner_cutting)
    assert paths.paths == want.paths


def test_plan_optimal_and_vin_from_the_cli(tmp_path, capsys):
    maps_file = tmp_path / "m.npz"
    assert (
        main(["maps", "generate", "--n", "5", "--size", "28", "--seed", "3", "--out", str(maps_file), "--quiet"]) == 0
    )
    capsys.readouterr()  # the maps' summary
    assert (
        main(["plan", "--maps", str(maps_file), "--out", str(tmp_path / "o.npz"), "--planner", "optimal", "--json"])
        == 0
    )
    optimal = json.loads(capsys.readouterr().out)
    assert optimal["reached"] == 1.0 and optimal["planner"]["weights_sha256"] is None
    assert main(["plan", "--maps", str(maps_file), "--out", str(tmp_path / "v.npz"), "--json"]) == 0
    vin = json.loads(capsys.readouterr().out)
    assert vin["planner"]["name"] == "vin" and len(vin["planner"]["weights_sha256"]) == 64
    assert PathSet.load(tmp_path / "v.npz").model.startswith("vin k=36 sha256=")


def test_planners_command(capsys):
    assert main(["planners", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert [p["name"] for p in out["planners"]] == REGISTERED
    assert main(["planners"]) == 0
    text = capsys.readouterr().out
    assert "optimal" in text and "FILE.py:FACTORY" in text


@pytest.fixture
def own_names():
    """Planners a test registers (names appended), unregistered after it."""
    names = []
    yield names
    for name in names:
        if name in registry.REGISTRY:
            registry.unregister(name)


def test_a_registered_planner_is_loaded_listed_and_refused_twice(own_names):
    own_names.append("mine")
    calls = []

    def load(size, weights, corner_cutting, device):
        calls.append((size, weights, corner_cutting, device))
        return OptimalPlanner(size, corner_cutting)

    registry.register("mine", description="my planner", load=load)
    planner = load_planner("mine", 12, corner_cutting=False)
    load_planner("mine", 12, device="auto")  # a device name reaches the loader checked and concrete
    expected = "cuda" if torch.cuda.is_available() else "cpu"
    assert isinstance(planner, OptimalPlanner) and calls == [(12, None, False, None), (12, None, True, expected)]
    assert list_planners(12)[-1] == {
        "name": "mine",
        "description": "my planner",
        "weights": None,
        "weights_available": None,
        "params": [],
    }
    with pytest.raises(PlannerError, match="planner 'mine' takes no weights file"):
        load_planner("mine", 12, weights="w.pt")
    with pytest.raises(InputError, match="'mine': a planner of that name is already registered"):
        registry.register("mine", description="again", load=load)
    for bad in ("my:planner", "mine+d4", " mine2", "", "a=b", "a,b"):
        with pytest.raises(InputError, match="would not read as a planner name"):
            registry.register(bad, description="bad", load=load)


def test_registering_the_planners_imports_no_pytorch():
    code = "import sys, vinadv.planners.registry as r; assert r.REGISTRY['gppn']; print('torch' in sys.modules)"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=True)
    assert done.stdout.strip() == "False"


def test_vin_weights_of_another_map_size_are_refused(tmp_path, capsys):
    # the shipped weights were trained on 28x28 maps: on 16x16 ones they would plan, badly and silently
    shipped = str(default_weights_path(28))
    with pytest.raises(InputError, match=r"VIN weights trained on 28x28 maps, the maps are 16x16"):
        load_planner("vin", 16, weights=shipped)
    maps_file = tmp_path / "m.npz"
    assert main(["maps", "generate", "--n", "1", "--size", "16", "--out", str(maps_file), "--quiet"]) == 0
    capsys.readouterr()
    out = tmp_path / "p.npz"
    assert main(["plan", "--maps", str(maps_file), "--weights", shipped, "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == f"vinadv: error: {shipped}: VIN weights trained on 28x28 maps, the maps are 16x16"
    assert not out.exists()
    assert load_planner("vin", 28, weights=shipped).size == 28  # the control: on their own size they load


def test_a_planner_without_parameters_records_no_weights_checksum(tmp_path):
    (tmp_path / "none.py").write_text(NO_PARAMETERS)
    planner = load_planner(f"{tmp_path / 'none.py'}:make", 8)
    assert planner.checksum is None and planner.spec()["weights_sha256"] is None
    assert len(planner.config["source_sha256"]) == 64  # its source is still identified
    (tmp_path / "one.py").write_text(EXAMPLE.read_text())
    assert len(load_planner(f"{tmp_path / 'one.py'}:make", 8).checksum) == 64  # one with weights has a checksum


def test_a_spec_gives_a_registered_planner_parameters_which_its_config_records():
    planner = load_planner("wastar:w=3", 16, moves="moore")
    assert isinstance(planner, WeightedAStarPlanner) and planner.w == 3.0 and planner.moves == "moore"
    assert planner.spec()["name"] == "wastar" and planner.spec()["config"] == {"moves": "moore", "w": 3.0}
    assert load_planner("wastar", 16).w == 2.0  # the default
    assert load_planner(" wastar : w = 1.5 ", 16).w == 1.5
    assert registry.split_spec("wastar:w=3,x=y") == ("wastar", {"w": "3", "x": "y"})
    assert registry.split_spec("pkg.mod:make") == ("pkg.mod:make", None)  # a factory never holds '='
    ref = registry.PlannerRef.of(planner, "wastar:w=3", None, True)
    assert ref.spec == "wastar:w=3" and ref.load().w == 3.0


@pytest.mark.parametrize(
    ("spec", "message"),
    [
        ("wastar:x=1", "planner 'wastar:x=1': unknown parameter 'x' (wastar takes w)"),
        ("astar:w=2", "planner 'astar:w=2': unknown parameter 'w' (astar takes no parameters)"),
        ("wastar:w=abc", "planner 'wastar:w=abc': parameter w must be a number >= 1, got 'abc'"),
        ("wastar:w=0.5", "parameter w must be a number >= 1, got '0.5'"),
        ("wastar:w=nan", "parameter w must be a number >= 1, got 'nan'"),
        ("wastar:w=2,w=3", "parameter 'w' is given twice"),
        ("wastar:w=2,", "parameters are key=value pairs separated by commas, got ''"),
        ("wastar:=2", "parameters are key=value pairs separated by commas, got '=2'"),
        ("nope:w=2", "key=value parameters follow a registered planner name"),
    ],
)
def test_bad_parameters_are_refused_in_one_line_naming_them(spec, message):
    with pytest.raises(PlannerError, match=re.escape(message)) as caught:
        load_planner(spec, 16)
    assert "\n" not in str(caught.value)


def test_a_registered_planner_takes_its_parameters_by_keyword(own_names):
    own_names.extend(["deep", "deeper"])
    calls = []

    def load(size, weights, corner_cutting, device, depth, scale):
        calls.append((depth, scale))
        return OptimalPlanner(size, corner_cutting)

    params = (registry.PlannerParam("depth", 3, "layers", minimum=1), registry.PlannerParam("scale", 0.5, "x"))
    registry.register("deep", description="d", load=load, params=params)
    load_planner("deep:scale=-2", 8)
    load_planner("deep", 8)
    assert calls == [(3, -2.0), (3, 0.5)] and isinstance(calls[0][0], int)
    with pytest.raises(PlannerError, match=r"parameter depth must be an integer >= 1, got '2.5'"):
        load_planner("deep:depth=2.5", 8)
    assert list_planners(8)[-1]["params"][0] == {"name": "depth", "default": 3, "minimum": 1, "description": "layers"}
    with pytest.raises(InputError, match="distinct identifiers"):
        registry.register("deeper", description="d", load=load, params=params[:1] * 2)


def test_the_cli_lists_parameters_and_refuses_bad_ones_with_exit_2(tmp_path, capsys):
    assert main(["planners", "--json"]) == 0
    wastar = next(p for p in json.loads(capsys.readouterr().out)["planners"] if p["name"] == "wastar")
    assert wastar["name"] == "wastar" and [p["name"] for p in wastar["params"]] == ["w"]
    assert main(["planners"]) == 0
    assert "[parameters w=2]" in capsys.readouterr().out
    maps_file = tmp_path / "m.npz"
    assert main(["maps", "generate", "--n", "1", "--size", "8", "--out", str(maps_file), "--quiet"]) == 0
    capsys.readouterr()
    out = tmp_path / "p.npz"
    assert main(["plan", "--maps", str(maps_file), "--planner", "wastar:w=x", "--out", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == "vinadv: error: planner 'wastar:w=x': parameter w must be a number >= 1, got 'x'"
    assert not out.exists()


@pytest.mark.parametrize("name", ["vin-mpd32", "gppn-mpd32"])
def test_the_mp_trained_planners_plan_32x32_moore_maps_and_refuse_others(name):
    maps = generate_maps(2, 32, seed=1, n_starts=1, moves="moore")
    planner = load_planner(name, 32, moves="moore")
    assert planner.name == name and planner.moves == "moore" and planner.spec()["name"] == name
    record = json.loads(registry.default_weights(name, 32).with_suffix(".json").read_text())
    assert record["moves"] == "moore" and record["size"] == 32  # what the refusals below read
    result = planner.plan(maps.obstacles, maps.starts, maps.goals)
    assert len(result.termination) == 2
    with pytest.raises(InputError, match=f"planner '{name}' plans moore moves .*the maps use 'octile' moves"):
        load_planner(name, 32)
    with pytest.raises(InputError, match="trained on 32x32 maps, the maps are 28x28"):
        load_planner(name, 28, moves="moore")
    with pytest.raises(PlannerError, match="takes no weights file"):
        load_planner(name, 32, weights="w.pt", moves="moore")


# --- names: one spelling (hyphens), the old ones still accepted -----------------------------------------------------

#: the names of earlier versions -> today's: planners (`--planner`) and zoo models (`--weights`)
OLD_PLANNERS = {"vin_robust": "vin-robust"}
OLD_WEIGHTS = {
    "vin28_robust": "vin28-robust",
    "vin_mpd32": "vin-mpd32",
    "gppn_mpd32": "gppn-mpd32",
    "neural_astar_mazes32": "neural-astar-mazes32",
    "neural_astar_mpd5": "neural-astar-mpd5",
}


def test_planners_json_lists_hyphenated_names_only(capsys):
    assert main(["planners", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    names = [p["name"] for p in out["planners"]] + [m["name"] for m in out["zoo"]]
    names += [p["zoo"] for p in out["planners"] if p["zoo"]] + [m["planner"] for m in out["zoo"]]
    assert names and not [n for n in names if "_" in n]
    assert not set(OLD_PLANNERS) & set(names) and not set(OLD_WEIGHTS) & set(names)


@pytest.mark.parametrize(
    ("spec", "weights", "name"),
    [
        ("vin_robust", None, "vin-robust"),
        ("vin", "vin28_robust", "vin-robust"),
        ("vin", "vin28-robust", "vin-robust"),
        ("vin-robust", "vin28_robust", "vin-robust"),
        ("vin_robust+d4", None, "vin-robust+d4"),
        ("vin", "vin_mpd32", "vin-mpd32"),
        ("gppn", "gppn_mpd32", "gppn-mpd32"),
        ("neural-astar", "neural_astar_mpd5", "neural-astar-mpd5"),
        ("neural-astar", "neural_astar_mazes32", "neural-astar"),
    ],
)
def test_old_names_and_a_family_with_shipped_weights_resolve_before_load(spec, weights, name):
    assert registry.resolve_choice(spec, weights)[0] == name
    assert registry.same_choice((spec, weights), (name, registry.resolve_choice(spec, weights)[1]))


def test_every_old_name_loads_the_planner_of_its_new_name():
    for old, new in OLD_PLANNERS.items():
        a, b = load_planner(old, 28), load_planner(new, 28)
        assert a.name == b.name == new and a.spec() == b.spec()
    for old, new in OLD_WEIGHTS.items():
        model = registry.zoo_model(new)
        family = registry.REGISTRY[model.planner].family
        size = model.size or 32
        a = load_planner(family, size, weights=old, moves=model.moves)
        b = load_planner(family, size, weights=new, moves=model.moves)
        assert a.name == b.name == model.planner and a.checksum == b.checksum == model.sha256, old
    with pytest.raises(PlannerError, match="takes no weights file"):
        load_planner("vin-robust", 28, weights="vin28")  # a fixed planner takes its own weights only
    with pytest.raises(InputError, match="name 'my_planner': planner names are spelled with hyphens"):
        registry.register("my_planner", description="x", entry_point="m:f")
    with pytest.raises(InputError, match="'vin_robust': a planner of that name is already registered"):
        registry.register("mine", description="x", entry_point="m:f", aliases=("vin_robust",))


@pytest.fixture(scope="module")
def maps28(tmp_path_factory):
    path = tmp_path_factory.mktemp("maps") / "m.npz"
    assert main(["maps", "generate", "--n", "2", "--size", "28", "--seed", "3", "--out", str(path), "--quiet"]) == 0
    return path


@pytest.mark.parametrize(
    "args",
    [["--planner", "vin_robust"], ["--planner", "vin", "--weights", "vin28_robust"], ["--planner", "vin-robust"]],
    ids=" ".join,
)
def test_the_cli_takes_old_names_as_planner_and_weights(args, maps28, tmp_path, capsys):
    out = tmp_path / "p.npz"
    assert main(["plan", "--maps", str(maps28), "--out", str(out), *args, "--json"]) == 0
    planner = json.loads(capsys.readouterr().out)["planner"]
    assert planner["name"] == "vin-robust" and planner["weights_sha256"] == registry.zoo_model("vin28-robust").sha256


def test_run_resume_takes_old_and_new_names_of_one_planner(tmp_path, capsys):
    db = f"sqlite:///{tmp_path / 'r.db'}"
    args = ["run", "--n", "4", "--size", "28", "--shard-size", "2", "--db", db, "--name", "r", "--quiet"]
    assert main([*args, "--planner", "vin_robust"]) == 0
    for choice in (["--planner", "vin-robust"], ["--planner", "vin", "--weights", "vin28-robust"]):
        assert main([*args, *choice, "--resume"]) == 0, capsys.readouterr().err
    assert main([*args, "--planner", "vin", "--resume"]) == 2  # another planner: refused
    assert "other settings (planner" in capsys.readouterr().err
