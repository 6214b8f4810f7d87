"""The user guide and the API reference cannot rot: the README is a guide of about 200 lines that
starts with the two commands and links every page of docs/, and the API reference of the scene
vocabulary is built from the docstrings (pdoc) with every public class of the model in it."""
import inspect
import re
from pathlib import Path

import pdoc  # noqa: F401  (the test extra: a missing pdoc is an install error, not a skip)

from app import apidoc
from workbench.scenes import model

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"


def test_readme_starts_with_the_two_commands():
    text = README.read_text()
    first = re.search(r"```bash\n(.*?)```", text, flags=re.S)
    assert text.index("```bash") < text.index("\n## "), "the commands come before any section"
    commands = [line for line in first.group(1).splitlines() if line.strip()]
    assert commands == ['python3 -m pip install -e . && workbench verify --quick',
                        'python3 -m pip install -e ".[test]" && python3 -m pytest -q']


def test_readme_is_a_guide_that_links_every_docs_page():
    text = README.read_text()
    # a guide of about 200 lines (the scene file of "Your own scene", which the tests run as
    # written, apart); the measurement record lives in docs/, the dynamic example in examples/
    scene_files = re.findall(r"```python\n# \w+\.py\n.*?```", text, flags=re.S)
    assert len(scene_files) == 1
    guide = len(text.splitlines()) - sum(len(b.splitlines()) for b in scene_files)
    assert guide <= 200, guide
    linked = set(re.findall(r"\]\((docs/[^)#]+)", text))
    pages = {f"docs/{p.name}" for p in (ROOT / "docs").glob("*.md")}
    assert pages, "docs/ holds the method notes and the measurement record"
    assert linked == pages, (linked ^ pages)
    for page in pages:  # every page has a title and text
        body = (ROOT / page).read_text()
        assert body.startswith("# ") and len(body.splitlines()) > 5, page


def test_api_reference_is_built_from_the_docstrings(tmp_path):
    index = apidoc.build(tmp_path)
    assert index.exists()
    html = (tmp_path / "workbench" / "scenes" / "model.html").read_text()
    public = [name for name, obj in vars(model).items()
              if inspect.isclass(obj) and obj.__module__ == model.__name__
              and not name.startswith("_") and obj.__doc__]
    assert len(public) >= 20  # Region, Set, Clamp, …, Explicit, Period, Model
    for name in public:
        assert f'id="{name}"' in html, name
        first_line = inspect.getdoc(getattr(model, name)).splitlines()[0]
        words = re.findall(r"[A-Za-z]{4,}", first_line)[:3]
        for w in words:  # the docstring's own words are on the page
            assert w in html, (name, w)


def test_workbench_docs_writes_the_reference(tmp_path, capsys):
    from app import cli

    assert cli.main(["docs", "--out", str(tmp_path / "api")]) == 0
    assert (tmp_path / "api" / "workbench" / "scenes" / "model.html").exists()
    assert "index.html" in capsys.readouterr().out
