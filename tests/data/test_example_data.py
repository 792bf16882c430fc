"""Example data: lazy mapping, offline errors, data folders, sha256 checks, fallbacks.

Downloads are exercised for real against a local HTTP server; the real
GitHub URL is exercised for what it is here: unreachable.
"""

from __future__ import annotations

import functools
import hashlib
import http.server
import socket
import threading
import warnings
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import rbm_nb as rbm
from rbm_nb.data import (
    ExampleDataStore,
    ExampleDataUnavailable,
    load_example,
    synthetic_head_eye,
)
from rbm_nb.data.registry import BASE_URL, DATA_DIR_ENV, REGISTRY
from rbm_nb.io import FileFormatError


def _github_reachable() -> bool:
    try:
        socket.create_connection(("github.com", 443), timeout=3).close()
        return True
    except OSError:
        return False


def _closed_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


@pytest.fixture(autouse=True)
def _isolated(monkeypatch, tmp_path):
    """No test touches the real cache folder or inherits RBM_NB_DATA_DIR."""
    monkeypatch.delenv(DATA_DIR_ENV, raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg-cache"))


@pytest.fixture(scope="module")
def files(tmp_path_factory) -> dict:
    """Small real files to serve and register: a head dataset and a bag."""
    folder = tmp_path_factory.mktemp("served")
    head = synthetic_head_eye(duration=15.0, seed=1).head
    head.to_netcdf(folder / "head.nc")
    rbm.data.write_synthetic_rosbag(folder / "example.bag", duration=15.0, seed=1)
    (folder / "left_eye.nc").write_bytes(b"this is not netCDF")
    return {"folder": folder, "head": head}


def _registry(folder: Path) -> dict:
    return {
        name: (filename, _sha256(folder / filename))
        for name, filename in (
            ("head", "head.nc"),
            ("rosbag", "example.bag"),
            ("left_eye", "left_eye.nc"),
        )
    }


@pytest.fixture
def server(files):
    """An HTTP server on localhost serving the files; yields (base_url, request log)."""
    requests_seen = []

    class Handler(http.server.SimpleHTTPRequestHandler):
        def log_message(self, fmt, *args):
            requests_seen.append(self.path)

    httpd = http.server.ThreadingHTTPServer(
        ("127.0.0.1", 0), functools.partial(Handler, directory=str(files["folder"]))
    )
    thread = threading.Thread(
        target=httpd.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True
    )
    thread.start()
    try:
        yield f"http://127.0.0.1:{httpd.server_address[1]}/", requests_seen
    finally:
        httpd.shutdown()
        httpd.server_close()
        thread.join()


def test_registry_is_the_real_one():
    assert BASE_URL == "https://github.com/phausamann/rbm-data/raw/main/"
    assert REGISTRY["head"] == (
        "head.nc",
        "874eddaa51bf775c7311f0046613c6f969adef6e34fe4aea2e1248a75ed3fee3",
    )
    assert (
        REGISTRY["left_eye"][1]
        == "56d5488fb8d3ff08450663ed0136ac659c1d51eb5340a7e3ed52f5ecf019139c"
    )
    assert (
        REGISTRY["right_eye"][1]
        == "b038c4cb2f6932e4334f135cdf7e24ff9c3b5789977b2ae0206ba80acf54c647"
    )
    assert REGISTRY["rosbag"] == (
        "example.bag",
        "8d27f5e554f5a0e02e0bec59b60424e582f6104380f96c3f226b4d85c107f2bc",
    )
    assert isinstance(rbm.example_data, ExampleDataStore)
    assert sorted(rbm.example_data) == ["head", "left_eye", "right_eye", "rosbag"]


def test_mapping_access_never_downloads(tmp_path):
    store = ExampleDataStore(
        base_url=f"http://127.0.0.1:{_closed_port()}/", data_dir=tmp_path
    )
    assert len(store) == 4 and "head" in store and "nope" not in store
    assert sorted(store) == ["head", "left_eye", "right_eye", "rosbag"]
    assert "head" in repr(store) and str(tmp_path) in repr(store)
    assert store.path("head") == tmp_path / "head.nc"
    assert not store.is_available("head")
    assert list(tmp_path.iterdir()) == []


def test_unknown_name():
    with pytest.raises(
        KeyError, match="'brain' is not an example dataset; choose one of"
    ):
        rbm.example_data["brain"]


def test_bad_registry_entry():
    with pytest.raises(ValueError, match="sha256 as 64 hex digits"):
        ExampleDataStore({"head": ("head.nc", "abc")})


def _check_offline_error(
    err: ExampleDataUnavailable, folder: Path, name: str = "head"
) -> None:
    import requests

    message = str(err)
    assert "could not be downloaded" in message
    assert DATA_DIR_ENV in message
    assert f"load_example('{name}', source='synthetic')" in message
    assert isinstance(err, OSError)
    # chained, not swallowed
    assert isinstance(err.__cause__, requests.RequestException)
    assert not folder.exists() or not any(p.is_file() for p in folder.rglob("*"))


@pytest.mark.skipif(
    _github_reachable(),
    reason="GitHub is reachable: the offline path cannot be exercised",
)
@pytest.mark.parametrize("folder_from", ["env", "default-cache"])
def test_real_github_unreachable(tmp_path, monkeypatch, folder_from):
    if folder_from == "env":
        monkeypatch.setenv(DATA_DIR_ENV, str(tmp_path / "data"))
        folder = tmp_path / "data"
    else:
        folder = tmp_path / "xdg-cache" / "rbm_nb"
    assert rbm.example_data.data_dir == folder
    with pytest.raises(ExampleDataUnavailable, match="github.com") as info:
        rbm.example_data["head"]
    _check_offline_error(info.value, folder)


def test_connection_refused(tmp_path):
    store = ExampleDataStore(
        base_url=f"http://127.0.0.1:{_closed_port()}/", data_dir=tmp_path / "d"
    )
    assert store.timeout[0] <= 5  # a short connect timeout: offline answers come fast
    with pytest.raises(
        ExampleDataUnavailable, match="could not connect to 127.0.0.1"
    ) as info:
        store["rosbag"]
    _check_offline_error(info.value, tmp_path / "d", "rosbag")


def test_folder_from_env_is_used_without_network(files, tmp_path, monkeypatch):
    folder = tmp_path / "mine"
    folder.mkdir()
    for name in ("head.nc", "example.bag"):
        (folder / name).write_bytes((files["folder"] / name).read_bytes())
    monkeypatch.setenv(DATA_DIR_ENV, str(folder))
    store = ExampleDataStore(
        _registry(files["folder"]), base_url=f"http://127.0.0.1:{_closed_port()}/"
    )
    assert store["head"] == folder / "head.nc" and store.is_available("head")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        head = load_example("head", store=store)  # "auto" finds it: no fallback warning
        bag = load_example("rosbag", source="remote", store=store)
    xr.testing.assert_identical(head, files["head"])
    assert bag == folder / "example.bag"


def test_hash_mismatch_in_chosen_folder_is_an_error(files, tmp_path, monkeypatch):
    folder = tmp_path / "mine"
    folder.mkdir()
    (folder / "head.nc").write_bytes(b"an old or damaged copy")
    monkeypatch.setenv(DATA_DIR_ENV, str(folder))
    registry = _registry(files["folder"])
    store = ExampleDataStore(registry, base_url=f"http://127.0.0.1:{_closed_port()}/")
    with pytest.raises(ExampleDataUnavailable) as info:
        store["head"]
    message = str(info.value)
    assert str(folder / "head.nc") in message and registry["head"][1] in message
    assert hashlib.sha256(b"an old or damaged copy").hexdigest() in message
    assert "not used" in message
    assert (folder / "head.nc").read_bytes() == b"an old or damaged copy"  # left alone
    with pytest.raises(ExampleDataUnavailable):
        load_example("head", source="remote", store=store)


def test_download_into_default_cache(files, server, tmp_path):
    base_url, seen = server
    store = ExampleDataStore(_registry(files["folder"]), base_url=base_url)
    path = store["head"]
    assert path == tmp_path / "xdg-cache" / "rbm_nb" / "head.nc"
    assert path.read_bytes() == (files["folder"] / "head.nc").read_bytes()
    assert seen == ["/head.nc"]
    assert store["head"] == path and seen == ["/head.nc"]  # cached: no second request
    xr.testing.assert_identical(
        load_example("head", source="remote", store=store), files["head"]
    )


def test_download_with_wrong_hash_is_discarded(files, server, tmp_path):
    base_url, seen = server
    registry = {"head": ("head.nc", "0" * 64)}
    store = ExampleDataStore(registry, base_url=base_url, data_dir=tmp_path / "d")
    with pytest.raises(
        ExampleDataUnavailable, match="does not have the registered sha256 0{64}"
    ) as info:
        store["head"]
    assert isinstance(info.value.__cause__, ValueError)
    assert seen == ["/head.nc"]
    # nothing left in the cache
    assert not any(p.is_file() for p in (tmp_path / "d").rglob("*"))


def test_damaged_cache_entry_is_downloaded_again(files, server, tmp_path):
    base_url, seen = server
    cache = tmp_path / "xdg-cache" / "rbm_nb"
    cache.mkdir(parents=True)
    (cache / "head.nc").write_bytes(b"truncated download from long ago")
    store = ExampleDataStore(_registry(files["folder"]), base_url=base_url)
    assert store["head"].read_bytes() == (files["folder"] / "head.nc").read_bytes()
    assert seen == ["/head.nc"]


def test_damaged_cache_entry_offline_is_dropped(files, tmp_path):
    cache = tmp_path / "xdg-cache" / "rbm_nb"
    cache.mkdir(parents=True)
    (cache / "head.nc").write_bytes(b"truncated download from long ago")
    store = ExampleDataStore(
        _registry(files["folder"]), base_url=f"http://127.0.0.1:{_closed_port()}/"
    )
    with pytest.raises(ExampleDataUnavailable):
        store["head"]
    assert not (cache / "head.nc").exists()  # a bad file is not left in the cache


def test_registered_file_that_is_not_netcdf(files, server):
    store = ExampleDataStore(_registry(files["folder"]), base_url=server[0])
    with pytest.raises(
        FileFormatError, match="left_eye.nc is not a readable netCDF file"
    ):
        load_example("left_eye", store=store)


def test_auto_falls_back_to_synthetic_with_a_warning(tmp_path):
    store = ExampleDataStore(
        base_url=f"http://127.0.0.1:{_closed_port()}/", data_dir=tmp_path
    )
    with pytest.warns(
        UserWarning, match="real head recording is unavailable, using the synthetic one"
    ) as record:
        head = load_example("head", store=store)
    assert DATA_DIR_ENV in str(record[0].message)
    assert head.attrs["source"] == "synthetic (rbm_nb)"
    assert head.sizes["time"] == 66000
    with pytest.raises(ExampleDataUnavailable):
        load_example("head", source="remote", store=store)


def test_synthetic_source_needs_no_network_and_gives_copies(tmp_path):
    store = ExampleDataStore(
        base_url=f"http://127.0.0.1:{_closed_port()}/", data_dir=tmp_path
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        eye = load_example("left_eye", source="synthetic", store=store)
    # read-only (frames keep it instead of copies); a deep copy is the user's
    with pytest.raises(ValueError, match="read-only"):
        eye.orientation.values[:] = 0.0
    eye = eye.copy(deep=True)
    eye.orientation.values[:] = 0.0
    again = load_example("left_eye", source="synthetic", store=store)
    q = again.orientation.values
    present = np.isfinite(q).all(axis=1)  # NaN rows: samples without data
    assert present.mean() > 0.6
    np.testing.assert_allclose(np.linalg.norm(q[present], axis=1), 1.0)
    assert list(tmp_path.iterdir()) == []


def test_load_example_arguments():
    with pytest.raises(ValueError, match="name must be one of"):
        load_example("brain")
    with pytest.raises(ValueError, match="source must be one of"):
        load_example("head", source="cloud")


@pytest.mark.network
@pytest.mark.skipif(not _github_reachable(), reason="GitHub is unreachable")
def test_real_download(tmp_path, monkeypatch):
    monkeypatch.setenv(DATA_DIR_ENV, str(tmp_path))
    path = rbm.example_data["left_eye"]
    assert _sha256(path) == REGISTRY["left_eye"][1]
    ds = load_example("left_eye", source="remote")
    assert {"time", "cartesian_axis", "quaternion_axis"} <= set(ds.dims)


# -- the real recordings, when they are beside the repo ------------------------


def _listing(folder: Path) -> dict:
    return {p.name: (p.stat().st_size, p.stat().st_mtime_ns) for p in folder.iterdir()}


@pytest.fixture
def real_dir():
    from recordings import REAL_DIR, real_available

    if not real_available():
        pytest.skip(f"the real recordings are not in {REAL_DIR}")
    return REAL_DIR


def test_real_files_load_from_the_data_folder_untouched(
    real_dir, monkeypatch, tmp_path
):
    monkeypatch.setenv(DATA_DIR_ENV, str(real_dir))
    monkeypatch.setenv("RBM_NB_CACHE_DIR", str(tmp_path / "cache"))
    before = _listing(real_dir)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no fallback: the real files are used
        for name in ("head", "left_eye", "right_eye"):
            ds = load_example(name, source="remote")
            xr.testing.assert_identical(ds, xr.load_dataset(real_dir / f"{name}.nc"))
    assert "source" not in ds.attrs  # not the synthetic recording
    assert _listing(real_dir) == before


@pytest.mark.slow
def test_rosbag_fallback_with_the_real_data_folder_writes_only_to_the_cache(
    real_dir, monkeypatch, tmp_path
):
    """The shared folder has the .nc files but no example.bag: the synthetic
    bag is built in the cache folder, the data folder is left as it was."""
    monkeypatch.setenv(DATA_DIR_ENV, str(real_dir))
    monkeypatch.setenv("RBM_NB_CACHE_DIR", str(tmp_path / "cache"))
    before = _listing(real_dir)
    store = ExampleDataStore(base_url=f"http://127.0.0.1:{_closed_port()}/")
    if store.is_available("rosbag"):
        pytest.skip("the real example.bag is there: no fallback to test")
    with pytest.warns(UserWarning, match="using the synthetic one"):
        path = load_example("rosbag", store=store)
    assert (tmp_path / "cache") in path.parents
    assert _listing(real_dir) == before
