"""The folder list is the architecture: one job per package, imports that form a DAG."""

from __future__ import annotations

import ast
import graphlib
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[2] / 'src'

#: Every Python package of src/ (a folder with package.xml and a module folder of its name).
PACKAGES = sorted(path.parent.name for path in SRC.glob('*/package.xml')
                  if (path.parent / path.parent.name).is_dir())

#: Longest module (lines): past about 400 a module usually holds two jobs.
MAX_MODULE_LINES = 450
#: The bringup package holds only launching and running the graph.
MAX_BRINGUP_LINES = 2500


def python_files(package: str) -> list[Path]:
    """The package's modules and its launch files."""
    root = SRC / package
    return sorted([*(root / package).rglob('*.py'), *(root / 'launch').glob('*.py')])


def imported_uvms_packages(path: Path) -> set[str]:
    """Our own packages (``uvms_*``) that a module imports, at any depth of the file."""
    roots = set()
    for node in ast.walk(ast.parse(path.read_text(), filename=str(path))):
        if isinstance(node, ast.Import):
            roots.update(alias.name.split('.')[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            roots.add(node.module.split('.')[0])
    return {root for root in roots if root.startswith('uvms_')}


def exec_depends(package: str) -> set[str]:
    """The ``exec_depend`` entries of the package's package.xml, read by a plain XML parser."""
    tree = ET.parse(SRC / package / 'package.xml')
    return {element.text or '' for element in tree.getroot().iter('exec_depend')}


def import_graph() -> dict[str, set[str]]:
    """Package -> our packages it imports (itself and interface packages left out)."""
    graph = {}
    for package in PACKAGES:
        imported = set().union(*(imported_uvms_packages(path) for path in python_files(package)))
        graph[package] = {name for name in imported if name != package and name != 'uvms_msgs'}
    return graph


def test_layout_holds_one_package_per_job() -> None:
    """Recording, analysis, viewing, sweeps and the command line are packages of their own."""
    assert {'uvms_recording', 'uvms_analysis', 'uvms_viz', 'uvms_sweep', 'uvms_cli',
            'uvms_bringup'} <= set(PACKAGES)


def test_package_imports_form_a_dag() -> None:
    """No package imports, even lazily, a package that imports it back."""
    sorter = graphlib.TopologicalSorter(import_graph())
    try:
        sorter.prepare()
    except graphlib.CycleError as error:
        pytest.fail(f'package import cycle: {" -> ".join(error.args[1])}')


@pytest.mark.parametrize('package', PACKAGES)
def test_every_imported_package_is_an_exec_depend(package: str) -> None:
    """Colcon orders the build by package.xml: what a package imports, it declares."""
    missing = import_graph()[package] - exec_depends(package)
    assert not missing, f'{package}/package.xml lacks exec_depend {sorted(missing)}'


@pytest.mark.parametrize('package', PACKAGES)
def test_no_module_holds_two_jobs(package: str) -> None:
    """Every module stays under the line budget of one job."""
    long = {str(path.relative_to(SRC)): n for path in python_files(package)
            if (n := len(path.read_text().splitlines())) > MAX_MODULE_LINES}
    assert not long, f'modules over {MAX_MODULE_LINES} lines: {long}'


def test_bringup_holds_only_the_graph_runners() -> None:
    """uvms_bringup stays small enough to read as launch file, scenarios and runners."""
    lines = sum(len(path.read_text().splitlines()) for path in python_files('uvms_bringup'))
    assert lines <= MAX_BRINGUP_LINES, f'uvms_bringup has {lines} lines'


def test_ray_is_imported_by_the_sweep_package_only() -> None:
    """Ray is the sweep package's dependency alone (an optional extra of the install)."""
    users = set()
    for package in PACKAGES:
        for path in python_files(package):
            tree = ast.parse(path.read_text(), filename=str(path))
            for node in ast.walk(tree):
                names = ([alias.name for alias in node.names] if isinstance(node, ast.Import)
                         else [node.module or ''] if isinstance(node, ast.ImportFrom) else [])
                if any(name.split('.')[0] == 'ray' for name in names):
                    users.add(package)
    assert users <= {'uvms_sweep'}, users


def test_test_modules_have_unique_basenames() -> None:
    """Pytest (rootdir imports) refuses to collect the suite when two test files share a name.

    Two branches each added a test_thruster_faults.py (unit and scenarios) and the merged
    suite stopped at collection: caught here, in a second, not by the whole run.
    """
    tests = Path(__file__).resolve().parents[1]
    seen: dict[str, Path] = {}
    clashes = []
    for path in sorted(tests.rglob('*.py')):
        if path.name in ('conftest.py', '__init__.py'):
            continue
        if path.name in seen:
            clashes.append((seen[path.name], path))
        seen.setdefault(path.name, path)
    assert not clashes, f'test modules with the same basename: {clashes}'
