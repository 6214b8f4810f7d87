"""A case is a folder (issue 39, item 4): a study with a scene of its own holds that scene, its
study and its notes in one package under studies/, the core's scene package names no case, and
each study's modules stay small (style: modules < ~600 lines, named after the concept they hold)."""
import importlib
import inspect
import pkgutil
from pathlib import Path

import pytest

import studies
import workbench.scenes

CASES = ("rc_beam", "microcantilever")
"""The studies whose scene is their own (the fracture cases of 003 and 000)."""
MAX_LINES = 600


def _files(name: str) -> list[Path]:
    """The source files of a study: its module, or every module of its folder."""
    mod = studies.get(name)
    path = Path(mod.__file__)
    return sorted(path.parent.glob("*.py")) if path.name == "__init__.py" else [path]


@pytest.mark.parametrize("name", CASES)
def test_a_case_is_a_folder_with_its_scene_and_notes(name):
    study = studies.get(name)
    folder = Path(study.__file__).parent
    assert Path(study.__file__).name == "__init__.py" and folder.name == name
    assert study.SCENE.__module__ == f"studies.{name}.scene"
    assert Path(inspect.getsourcefile(study.SCENE)).parent == folder
    notes = (folder / "notes.md").read_text()
    assert notes.startswith("# ") and len(notes.splitlines()) > 5


def test_the_root_ladder_is_the_micro_cantilevers():
    root = studies.get("microcantilever_root")
    assert root.__name__ == "studies.microcantilever.root"
    assert root.SCENE is studies.get("microcantilever").SCENE


def test_the_core_scene_package_names_no_case():
    names = set(vars(workbench.scenes)) | {m.name for m in pkgutil.iter_modules(
        workbench.scenes.__path__)}
    for case in CASES:
        cls = studies.get(case).SCENE.__name__
        assert cls not in names and case not in names, (case, cls)
    assert not any(n.endswith("FRACTURE_SCENES") for n in names)


@pytest.mark.parametrize("name", sorted(studies.STUDIES))
def test_every_study_module_is_small(name):
    long = {str(p.relative_to(Path(studies.__file__).parent)): n for p in _files(name)
            if (n := len(p.read_text().splitlines())) >= MAX_LINES}
    assert not long, long


@pytest.mark.parametrize("name", CASES)
def test_the_package_exposes_the_study_protocol(name):
    """What studies.get(name), the CLI, verify and report read, and the gates' tolerances."""
    study = importlib.import_module(f"studies.{name}")
    for attr in ("NAME", "SCENE", "SOLVERS", "RESOLUTIONS", "QUICK_RESOLUTIONS", "N_GATES",
                 "ERROR_LABEL", "run", "gates", "errors", "plot", "report_notes", "TOL_ENERGY"):
        assert hasattr(study, attr), (name, attr)
    assert study.NAME == name
    assert study.__doc__.splitlines()[0].strip()
