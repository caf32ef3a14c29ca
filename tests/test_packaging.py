"""The package installs beside others and carries everything it needs."""

from __future__ import annotations

import pathlib
import subprocess
import sys
import tomllib

REPO = pathlib.Path(__file__).resolve().parent.parent


def test_library_folders_install_inside_the_mbd3d_namespace():
    config = tomllib.loads((REPO / "pyproject.toml").read_text())
    setuptools = config["tool"]["setuptools"]
    assert all(name == "mbd3d" or name.startswith("mbd3d.") for name in setuptools["packages"])
    assert setuptools["package-dir"] == {"mbd3d.planar": "planar", "mbd3d.joints": "joints",
                                         "mbd3d.viewer": "viewer"}
    project = config["project"]
    assert project["requires-python"] == ">=3.11"  # rerun-sdk 0.41 has no wheel below 3.11
    assert project["license"] == "MIT" and (REPO / "LICENSE").read_text().startswith("MIT")
    assert (REPO / "mbd3d" / "py.typed").exists()


def test_every_subpackage_is_installed():
    """A sub-package missing from pyproject's list imports from the checkout and fails after
    pip install (mbd3d.numerics.compiled once did)."""
    listed = set(tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]
                 ["packages"])
    found = {"mbd3d." + ".".join(init.parent.relative_to(REPO / "mbd3d").parts)
             for init in (REPO / "mbd3d").glob("*/**/__init__.py")}
    assert found <= listed, sorted(found - listed)


def test_nothing_in_the_repository_reads_the_developers_notes_beside_it():
    """Users clone the repository alone: the notes folder beside the developers' clone is not
    theirs."""
    tracked = subprocess.run(["git", "ls-files"], cwd=REPO, capture_output=True, text=True,
                             check=True).stdout.split()
    notes = "shared"  # the folder's name, spelt apart so that this file does not match itself
    patterns = (f"../{notes}", f'/ "{notes}"', f"{notes}/validation")
    offenders = []
    for name in tracked:
        path = REPO / name
        if path.suffix not in {".py", ".md", ".toml", ".txt", ""} or not path.is_file():
            continue
        text = path.read_text(errors="replace")
        if any(pattern in text for pattern in patterns):
            offenders.append(name)
    assert offenders == [], offenders


def test_no_code_imports_the_bare_folder_names():
    """In the wheel there is no top-level joints, planar or viewer: importing everything from
    a checkout (repository on the path) must not touch those names."""
    code = ("import sys, mbd3d, mbd3d.joints, mbd3d.planar, mbd3d.viewer, mbd3d.mechanisms,"
            " mbd3d.sweeps; print(sorted({'joints', 'planar', 'viewer'} & set(sys.modules)))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         cwd="/", env={"PYTHONPATH": str(REPO)}, check=True).stdout
    assert out.strip() == "[]"
