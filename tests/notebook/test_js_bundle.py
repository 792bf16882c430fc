"""The committed JavaScript bundles are what the sources build to.

rbm_nb/widgets/static/*.js are package data built from js/src by esbuild
(js/build.mjs). This rebuilds them into a temporary folder and compares bytes,
so a source edit without a rebuild (or a hand edit of a bundle) fails here.
"""

from __future__ import annotations

import shutil
import subprocess

import pytest
from conftest import REPO

JS = REPO / "js"
STATIC = REPO / "rbm_nb" / "widgets" / "static"


def _entries() -> list[str]:
    return sorted(p.name for p in (JS / "src").glob("*.js"))


def test_every_entry_has_a_committed_bundle():
    assert _entries(), "js/src has no entries"
    assert sorted(p.name for p in STATIC.glob("*.js")) == _entries()


def test_lock_file_is_committed_with_the_manifest():
    lock = (JS / "package-lock.json").read_text()
    assert '"lockfileVersion"' in lock
    assert '"esbuild"' in lock


@pytest.fixture(scope="module")
def fresh_build(tmp_path_factory):
    node, npm = shutil.which("node"), shutil.which("npm")
    if node is None or npm is None:
        pytest.skip("node/npm not installed: cannot rebuild the JS bundles here")
    if not (JS / "node_modules" / "esbuild").is_dir():
        done = subprocess.run(
            [npm, "--prefix", str(JS), "ci", "--no-audit", "--no-fund"],
            capture_output=True,
            text=True,
            timeout=600,
        )
        if done.returncode != 0:
            pytest.skip(f"npm ci failed (registry unreachable?): {done.stderr[-500:]}")
    out = tmp_path_factory.mktemp("bundles")
    subprocess.run(
        [node, str(JS / "build.mjs"), "--outdir", str(out)],
        check=True,
        capture_output=True,
        timeout=300,
    )
    return out


def test_committed_bundles_match_a_fresh_build(fresh_build):
    for name in _entries():
        built = (fresh_build / name).read_bytes()
        committed = (STATIC / name).read_bytes()
        assert built == committed, (
            f"rbm_nb/widgets/static/{name} differs from a fresh build of js/src/{name}; "
            "run: npm --prefix js ci && npm --prefix js run build"
        )


EMBED = JS / "embed"
EMBED_OUT = REPO / "docs" / "_static" / "widgets"


@pytest.fixture(scope="module")
def fresh_embed_build(tmp_path_factory):
    node, npm = shutil.which("node"), shutil.which("npm")
    if node is None or npm is None:
        pytest.skip("node/npm not installed: cannot rebuild the docs' widget manager")
    if not (EMBED / "node_modules" / "@jupyter-widgets" / "html-manager").is_dir():
        done = subprocess.run(
            [npm, "--prefix", str(EMBED), "ci", "--no-audit", "--no-fund"],
            capture_output=True,
            text=True,
            timeout=900,
        )
        if done.returncode != 0:
            pytest.skip(f"npm ci failed (registry unreachable?): {done.stderr[-500:]}")
    out = tmp_path_factory.mktemp("embed")
    subprocess.run(
        [node, str(EMBED / "build.mjs"), "--outdir", str(out)],
        check=True,
        capture_output=True,
        timeout=600,
    )
    return out


@pytest.mark.slow
def test_docs_widget_manager_matches_a_fresh_build(fresh_embed_build):
    """docs/_static/widgets is what js/embed builds to (html-manager + anywidget)."""
    built = sorted(p.name for p in fresh_embed_build.iterdir())
    assert built == sorted(p.name for p in EMBED_OUT.iterdir())
    for name in built:
        assert (fresh_embed_build / name).read_bytes() == (
            EMBED_OUT / name
        ).read_bytes(), (
            f"docs/_static/widgets/{name} differs from a fresh build; run: "
            "npm --prefix js/embed ci && node js/embed/build.mjs"
        )
