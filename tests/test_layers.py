"""The library's layering, read off the folders.

- physics (``core``, ``reynolds``, ``rotor``, ``characteristics``) never imports learning (``data``,
  ``surrogate``, ``control``), timing (``perf``), studies, reporting or the workflow;
- learning never imports studies, reporting or the workflow;
- surrogates depend on the dataset, never on the solver; the solver never on surrogates;
- Hydra, OmegaConf and MLflow are imported in ``fluidfilm.workflow`` alone (and by the entry points).

Checked on the static import graph (every import statement, module level and inside functions),
without the top-level ``fluidfilm/__init__.py``, which re-exports everything for users, and
without the lazy re-exports of a package's module ``__getattr__``.
"""
from __future__ import annotations

import ast
import re

import pytest
from test_dvc_deps import SRC, _module_file


def _deps_of(module: str) -> set[str]:
    path = _module_file(module)
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    tree = ast.parse(path.read_text())
    lazy = {id(n) for f in tree.body if isinstance(f, ast.FunctionDef) and f.name == "__getattr__"
            for n in ast.walk(f)}
    out = set()
    for node in ast.walk(tree):
        if id(node) in lazy:
            continue
        if isinstance(node, ast.Import):
            out |= {a.name for a in node.names if a.name.startswith("fluidfilm.")}
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                parts = package.split(".")
                base = ".".join(parts[:len(parts) - node.level + 1])
                target = f"{base}.{node.module}" if node.module else base
            else:
                target = node.module or ""
            if not target.startswith("fluidfilm."):
                continue
            out.add(target)
            out |= {f"{target}.{a.name}" for a in node.names if _module_file(f"{target}.{a.name}")}
    # parents run first (not the top-level package)
    return {".".join(m.split(".")[:k]) for m in out for k in range(2, m.count(".") + 2)}


def closure(module: str) -> set[str]:
    seen, todo = set(), {module}
    while todo:
        m = todo.pop()
        if m in seen or _module_file(m) is None:
            continue
        seen.add(m)
        todo |= _deps_of(m) - seen
    return seen


def _modules(package: str) -> list[str]:
    root = SRC / "fluidfilm" / package
    return sorted(f"fluidfilm.{package}." + p.relative_to(root).with_suffix("").as_posix().replace("/", ".")
                  for p in root.rglob("*.py") if p.name != "__init__.py")


@pytest.mark.parametrize("module", _modules("surrogate"))
def test_surrogates_do_not_import_the_solver(module):
    assert not {m for m in closure(module) if m.startswith("fluidfilm.reynolds")}, module


@pytest.mark.parametrize("module", _modules("reynolds") + _modules("data"))
def test_solver_and_data_do_not_import_surrogates(module):
    assert not {m for m in closure(module) if m.startswith("fluidfilm.surrogate")}, module


def test_the_layering_check_sees_a_real_dependency():
    """It can fail: the generator does import the solver, the scaling module's user does import scaling."""
    assert "fluidfilm.reynolds.policy" in closure("fluidfilm.data.generate")
    assert "fluidfilm.surrogate.scaling" in closure("fluidfilm.surrogate.fit")


def test_only_the_tracking_module_imports_mlflow():
    """MLflow is reached through fluidfilm.workflow.tracking alone (library and entry points)."""
    root = SRC.parent
    offenders = []
    for path in sorted(list((SRC / "fluidfilm").rglob("*.py")) + list((root / "experiments").glob("*.py"))):
        if path == SRC / "fluidfilm" / "workflow" / "tracking.py":
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                [node.module or ""] if isinstance(node, ast.ImportFrom) else []
            if any(n.split(".")[0] == "mlflow" for n in names):
                offenders.append(str(path.relative_to(root)))
    assert not offenders, f"import mlflow through fluidfilm.workflow.tracking instead: {sorted(set(offenders))}"


PHYSICS = ("core", "reynolds", "rotor", "characteristics")
LEARNING = ("data", "surrogate", "control")
ABOVE_LEARNING = ("perf", "studies", "reporting", "workflow")


def _layer_modules(layers) -> list[str]:
    return [m for layer in layers for m in _modules(layer)]


@pytest.mark.parametrize("module", _layer_modules(PHYSICS))
def test_physics_never_imports_learning_or_what_sits_above(module):
    banned = tuple(f"fluidfilm.{p}" for p in LEARNING + ABOVE_LEARNING)
    assert not {m for m in closure(module) if m.startswith(banned)}, module


@pytest.mark.parametrize("module", _layer_modules(LEARNING))
def test_learning_never_imports_studies_reporting_or_the_workflow(module):
    banned = tuple(f"fluidfilm.{p}" for p in ("studies", "reporting", "workflow"))
    assert not {m for m in closure(module) if m.startswith(banned)}, module


def test_hydra_and_mlflow_are_imported_in_the_workflow_layer_alone():
    offenders = []
    for path in sorted((SRC / "fluidfilm").rglob("*.py")):
        if (SRC / "fluidfilm" / "workflow") in path.parents:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
                [node.module or ""] if isinstance(node, ast.ImportFrom) and not node.level else []
            if any(n.split(".")[0] in ("hydra", "omegaconf", "mlflow") for n in names):
                offenders.append(str(path.relative_to(SRC)))
    assert not offenders, f"Hydra/OmegaConf/MLflow outside fluidfilm.workflow: {sorted(set(offenders))}"


def test_the_package_root_holds_a_handful_of_modules():
    """Subpackages by role; at most six modules directly under src/fluidfilm (``__init__`` included)."""
    root = sorted(p.name for p in (SRC / "fluidfilm").glob("*.py"))
    assert len(root) <= 6, root


def test_the_physics_check_sees_a_real_dependency():
    """It can fail: the rotor integrator does import the force-model contract in core."""
    assert "fluidfilm.core.force_model" in closure("fluidfilm.rotor.integrate")


def _imports_ross(path) -> list[tuple[int, bool]]:
    """(line, at module level) of every ``import ross`` / ``from ross... import`` in a file."""
    tree = ast.parse(path.read_text())
    top = {id(n) for n in tree.body}
    out = []
    for node in ast.walk(tree):
        names = [a.name for a in node.names] if isinstance(node, ast.Import) else \
            [node.module or ""] if isinstance(node, ast.ImportFrom) and not node.level else []
        if any(n.split(".")[0] == "ross" for n in names):
            out.append((node.lineno, id(node) in top))
    return out


def test_ross_is_imported_by_the_interop_adapter_alone_and_lazily():
    """ROSS (an optional extra, Python >= 3.13) is reached through fluidfilm.interop.ross only, and that module
    imports it inside its functions, so the package imports without ROSS; no other layer imports interop."""
    interop = SRC / "fluidfilm" / "interop" / "ross.py"
    offenders = [str(p.relative_to(SRC)) for p in sorted((SRC / "fluidfilm").rglob("*.py"))
                 if p != interop and _imports_ross(p)]
    assert not offenders, f"ROSS imported outside fluidfilm.interop.ross: {offenders}"
    found = _imports_ross(interop)
    assert found, "the adapter no longer imports ross: this check would pass vacuously"
    assert not [line for line, top in found if top], f"module-level ROSS imports in interop/ross.py: {found}"
    users = [m for layer in PHYSICS + LEARNING + ABOVE_LEARNING for m in _modules(layer)
             if any(d.startswith("fluidfilm.interop") for d in closure(m))]
    assert not users, f"modules that import fluidfilm.interop (it sits on top, for users): {users}"


#: what `pip install fluidfilm` (the lean core) does not install: the extras' packages (learn, workspace, ross)
HEAVY = ("torch", "lightning", "pytorch_lightning", "mlflow", "dvc", "hydra", "omegaconf", "dask", "distributed",
         "gymnasium", "stable_baselines3", "pyarrow", "matplotlib", "ross")

# run in a subprocess: a meta-path finder makes every import of HEAVY raise ModuleNotFoundError (as in a core-only
# install), then the core is imported and used; sys.modules is checked afterwards
_CORE_USE = """
import sys

HEAVY = {heavy!r}


class Blocker:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in HEAVY:
            raise ModuleNotFoundError(f"blocked: {{name}} is not part of the lean core", name=name)
        return None


sys.meta_path.insert(0, Blocker())
import fluidfilm
import fluidfilm.characteristics
import fluidfilm.rotor
import fluidfilm.surrogate.universal
from fluidfilm import JournalBearing, ReynoldsSolver, Rotor, equilibrium, simulate, universal_bearing
from fluidfilm.characteristics import bearing_characteristics, threshold_speed

b = JournalBearing(length=0.025, diameter=0.05, clearance=50e-6, speed_rpm=6000.0, viscosity=0.02)
solver = ReynoldsSolver(b, n_theta=20, n_z=10)
W = Rotor(mass=50.0).static_load()
eq = equilibrium(solver, W)
op = bearing_characteristics(solver, W)
traj = simulate(solver, Rotor(mass=50.0), t_end=0.002, x0=[eq["X1"], eq["X2"]])
model = universal_bearing(b)
assert model.forces([0.0, 20e-6], [0.0, 0.0]).shape == (2,)
assert threshold_speed(model, mass=50.0, load=W)["speed_rpm"] > 0
fluidfilm.equilibrium_locus(model, [100.0, 200.0])
assert traj.status == "ok", traj.status
loaded = sorted({{m.split(".")[0] for m in sys.modules}} & set(HEAVY))
assert not loaded, loaded
print("core ok")
"""


def test_the_core_runs_with_the_heavy_packages_blocked():
    """``pip install fluidfilm`` is the lean core: the package, the rotor, the characteristics and the shipped
    universal surrogate import and run with torch, Lightning, MLflow, DVC, Hydra, Dask, gymnasium,
    stable-baselines3, pyarrow, matplotlib and ROSS unimportable (a meta-path blocker makes them raise), and
    none of them ends up in ``sys.modules``. ``.ci/wheel_check`` does the same from the built wheel in a fresh
    Python 3.13 environment (the README's library blocks)."""
    import os
    import subprocess
    import sys

    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.run([sys.executable, "-c", _CORE_USE.format(heavy=HEAVY)], env=env, capture_output=True,
                          text=True, timeout=600)
    assert proc.returncode == 0 and "core ok" in proc.stdout, proc.stderr[-3000:]


def test_the_blocker_does_block():
    """It can fail: with the blocker in place, importing a workspace module that needs torch raises."""
    import os
    import subprocess
    import sys

    code = _CORE_USE.format(heavy=HEAVY).split("import fluidfilm\n")[0] + "import fluidfilm.surrogate.training.lightning\n"
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, timeout=600)
    assert proc.returncode != 0 and "blocked:" in proc.stderr, proc.stderr[-3000:]


def test_the_ross_element_without_ross_names_the_extra():
    """``fluidfilm.interop.ross.FluidFilmBearingElement`` is a ROSS BearingElement built on first use; where ROSS
    is not installed, making one says how to get it, and nothing is an instance of it."""
    import importlib.util

    if importlib.util.find_spec("ross") is not None:
        pytest.skip("ROSS is installed here: tests/interop/test_ross_adapter.py checks the element itself")
    from fluidfilm.interop import ross as fr

    assert not isinstance(object(), fr.FluidFilmBearingElement)
    with pytest.raises(ImportError, match=r'pip install "fluidfilm\[ross\]"'):
        fr.FluidFilmBearingElement(n=0, model=None, load=(0.0, -100.0))


#: the rooms (subpackages) and the rooms each may import directly besides itself and the root's utilities
#: (``fluidfilm.io``, ``fluidfilm.progress``): the table of docs/architecture.md, checked against it below
ROOMS: dict[str, tuple[str, ...]] = {
    "core": (),
    "reynolds": ("core",),
    "rotor": ("core", "reynolds"),
    "characteristics": ("core", "reynolds", "rotor"),
    "interop": ("core", "characteristics"),
    "data": ("core", "reynolds"),
    "surrogate": ("core", "data"),
    "control": ("core", "rotor"),
    "estimation": ("core", "characteristics", "surrogate"),
    "perf": ("core", "rotor", "surrogate"),
    "reporting": ("characteristics", "perf"),
    "workflow": ("core", "perf", "reporting", "reynolds", "surrogate"),
    "studies": ("core", "reynolds", "rotor", "characteristics", "interop", "data", "surrogate", "control",
                "estimation", "perf", "reporting", "workflow"),
}
UTILITIES = ("fluidfilm.io", "fluidfilm.progress")


def _room_imports(module: str) -> set[str]:
    """The rooms a module imports directly (not through what they import), the utilities left out."""
    out = set()
    for dep in _deps_of(module):
        if dep in UTILITIES or dep == "fluidfilm":
            continue
        room = dep.split(".")[1]
        if room not in ROOMS:
            out.add(dep)  # a root module other than the utilities (fluidfilm._conformance)
        else:
            out.add(room)
    return out


def test_every_room_is_in_the_table():
    rooms = sorted(p.parent.name for p in (SRC / "fluidfilm").glob("*/__init__.py"))
    assert rooms == sorted(ROOMS), "a room without a row in ROOMS (and docs/architecture.md), or a row without a room"


@pytest.mark.parametrize("room", sorted(ROOMS))
def test_each_room_imports_only_what_its_row_allows(room):
    offenders = {}
    for module in _modules(room) + [f"fluidfilm.{room}"]:
        extra = _room_imports(module) - set(ROOMS[room]) - {room}
        if extra:
            offenders[module] = sorted(extra)
    assert not offenders, f"imports against docs/architecture.md's table: {offenders}"


def test_the_architecture_page_states_the_rooms_rules():
    """docs/architecture.md's table names each room's allowed imports as ROOMS does, and its tests' folder
    (tests/<room>/); the page names every module of ``TOP_LEVEL``."""
    page = (SRC.parent / "docs" / "architecture.md").read_text()
    rows, tests = {}, {}
    for line in page.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 4 and re.fullmatch(r"`\w+`", cells[0]) and cells[0].strip("`") in ROOMS:
            allowed = cells[2]
            rows[cells[0].strip("`")] = (tuple(ROOMS) if allowed == "every room" else
                                         tuple(re.findall(r"`(\w+)`", allowed)))
            tests[cells[0].strip("`")] = cells[3]
    assert set(rows) == set(ROOMS), sorted(set(ROOMS) ^ set(rows))
    for room, allowed in ROOMS.items():
        want = set(allowed) if room != "studies" else set(ROOMS) - {"studies"}
        got = set(rows[room]) - {room}
        assert got == want, (room, sorted(got), sorted(want))
        assert tests[room] == f"`tests/{room}/`", (room, tests[room])
    assert not [name for name in TOP_LEVEL if f"`{name}`" not in page], "a TOP_LEVEL test the page does not name"


def test_the_room_check_sees_a_real_import():
    """It can fail: the rotor's integrator imports core, the dataset's generator the solver."""
    assert "core" in _room_imports("fluidfilm.rotor.integrate")
    assert "reynolds" in _room_imports("fluidfilm.data.generate")


# --- the tests mirror the rooms ---------------------------------------------------------------------------
TESTS = SRC.parent / "tests"
#: the test modules at the top of tests/, each spanning the rooms by design (docs/architecture.md says why);
#: every other test module sits in tests/<room>/ (or the fault-injection suite, tests/faults/)
TOP_LEVEL = {
    "test_docs.py": "the README and docs: their names, links, cited tests and worked example, every room's",
    "test_docstrings.py": "the public API of every room: its docstrings",
    "test_doctests.py": "the public API of every room: its Examples",
    "test_layers.py": "the rooms' import rules, and this mirror",
    "test_dvc_deps.py": "every stage of dvc.yaml, whatever rooms it imports",
    "test_pipeline.py": "`make reproduce` end to end",
    "test_quickstart.py": "the README's quickstart in a fresh clone, the citation and licence files",
    "test_slow.py": "the slow suite (`make test-slow`): the paper-scale dataset and every benchmark script",
    "test_tooling.py": "the repository's tooling: the root's io (stage tables) and DVC's settings",
}
OTHER_FOLDERS = ("faults", "__pycache__")


def _package_names() -> dict[str, str]:
    """The room of each name ``fluidfilm/__init__.py`` re-exports (``from fluidfilm import X``), read statically."""
    out = {}
    for node in ast.parse((SRC / "fluidfilm" / "__init__.py").read_text()).body:
        if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("fluidfilm."):
            out |= {a.asname or a.name: node.module.split(".")[1] for a in node.names}
    return out


def _rooms_a_test_imports(path) -> set[str]:
    """The rooms a test module imports anything of (every import statement, module level or not)."""
    names = _package_names()
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Import):
            out |= {a.name.split(".")[1] for a in node.names if a.name.startswith("fluidfilm.")}
        elif isinstance(node, ast.ImportFrom) and not node.level:
            module = node.module or ""
            if module.startswith("fluidfilm."):
                out.add(module.split(".")[1])
            elif module == "fluidfilm":
                out |= {names.get(a.name, a.name) for a in node.names}
    return out & set(ROOMS)


def _misplaced(path) -> str | None:
    """Why a test module in tests/<room>/ does not look like that room's: it imports the library but nothing of
    the room; or, importing nothing of the library (it runs entry points, reads files), its docstring does not
    name the room (``reporting/readme.py``, ``workflow.entry``).  None where it does."""
    room = path.parent.name
    imported = _rooms_a_test_imports(path)
    if room in imported:
        return None
    if imported:
        return f"imports {sorted(imported)}, nothing of {room}"
    doc = ast.get_docstring(ast.parse(path.read_text())) or ""
    return None if re.search(rf"\b{room}[./]\w", doc) else f"imports nothing of the library; its docstring names no {room}"


def test_the_tests_mirror_the_rooms():
    """tests/<room>/ for every room and no other folder (but tests/faults); each holds test modules of its room
    (``_misplaced``), and a test module at the top of tests/ is one of ``TOP_LEVEL``."""
    folders = sorted(p.name for p in TESTS.iterdir() if p.is_dir() and p.name not in OTHER_FOLDERS)
    assert folders == sorted(ROOMS), f"tests/ folders that are no room, or rooms without tests/<room>/: " \
                                     f"{sorted(set(folders) ^ set(ROOMS))}"
    empty = [room for room in ROOMS if not list((TESTS / room).glob("test_*.py"))]
    assert not empty, f"rooms without a test module in tests/<room>/: {empty}"
    top = sorted(p.name for p in TESTS.glob("test_*.py"))
    assert top == sorted(TOP_LEVEL), f"put a room's test in tests/<room>/ (or list a test spanning the rooms in " \
                                     f"TOP_LEVEL, with the reason): {sorted(set(top) ^ set(TOP_LEVEL))}"
    wrong = {str(p.relative_to(TESTS)): why for room in ROOMS for p in sorted((TESTS / room).glob("test_*.py"))
             if (why := _misplaced(p))}
    assert not wrong, f"test modules in another room's folder (move them to the room they test): {wrong}"


def test_the_mirror_check_sees_a_misplaced_test(tmp_path):
    """It can fail: the solver's test in surrogate/ is misplaced, in reynolds/ it is not; a module importing
    nothing of the library is placed by its docstring."""
    solver_test = (TESTS / "reynolds" / "test_reynolds.py").read_text()
    assert _misplaced(TESTS / "reynolds" / "test_reynolds.py") is None
    for room, body, placed in (("surrogate", solver_test, False), ("reynolds", solver_test, True),
                               ("workflow", '"""Every entry point runs (``workflow.entry``)."""\n', True),
                               ("studies", '"""Every entry point runs."""\n', False)):
        (tmp_path / room).mkdir(exist_ok=True)
        path = tmp_path / room / "test_probe.py"
        path.write_text(body)
        assert (_misplaced(path) is None) == placed, (room, _misplaced(path))
