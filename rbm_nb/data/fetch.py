"""Fetching the real example recordings with pooch, with errors that say what to do."""

from __future__ import annotations

import hashlib
import os
import re
from collections.abc import Iterator, Mapping
from pathlib import Path

# the folder rules, shared with rbm_nb.ros; also importable from here
from .._infra.folders import CACHE_DIR_ENV as CACHE_DIR_ENV
from .._infra.folders import DATA_DIR_ENV, env_folder
from .._infra.folders import cache_dir as cache_dir
from .._infra.folders import example_data_dirs as example_data_dirs
from .._infra.folders import pooch_module as _pooch
from .._infra.progress import download_bar
from .registry import BASE_URL, REGISTRY

# connect fast or give up: offline, an answer within seconds beats a long hang
DEFAULT_TIMEOUT = (3.05, 60.0)  # (connect, read) seconds


class ExampleDataUnavailable(OSError):
    """An example file is neither in the data folder nor downloadable.

    The message says why and how to get going: point ``RBM_NB_DATA_DIR`` to a
    folder with the files, or use the synthetic recording.
    """


class ExampleDataStore(Mapping):
    """Example files by name, downloaded on first access and checked by sha256.

    ``store["head"]`` returns the local :class:`pathlib.Path` of ``head.nc``,
    downloading it first if needed. Creating the store, listing it or testing
    ``"head" in store`` never touches the network.

    Parameters
    ----------
    registry : dict, optional
        ``{name: (file name, sha256)}``; default: the real example data.
    base_url : str, optional
        URL the file names are appended to.
    data_dir : str or path-like, optional
        Folder of the files. Default: the environment variable
        ``RBM_NB_DATA_DIR`` if set (read at each access), else pooch's cache
        folder for rbm_nb.
    timeout : float or (float, float)
        Connect (and read) timeout of downloads in seconds.

    Notes
    -----
    A file whose sha256 does not match is never used. In pooch's cache it is
    deleted and downloaded again; in a folder you chose (``data_dir`` or
    ``RBM_NB_DATA_DIR``) it is left alone and an error says so. A download
    that does not match is discarded.
    """

    def __init__(
        self,
        registry: Mapping[str, tuple[str, str]] | None = None,
        *,
        base_url: str = BASE_URL,
        data_dir: str | os.PathLike | None = None,
        timeout: float | tuple[float, float] = DEFAULT_TIMEOUT,
    ) -> None:
        registry = dict(REGISTRY if registry is None else registry)
        for name, entry in registry.items():
            if not (
                isinstance(entry, tuple)
                and len(entry) == 2
                and re.fullmatch(r"[0-9a-f]{64}", str(entry[1]))
            ):
                raise ValueError(
                    f"registry entry {name!r} must be (file name, sha256 as 64 hex digits), got {entry!r}"
                )
        self.registry = registry
        self.base_url = base_url
        self.timeout = timeout
        self._data_dir = None if data_dir is None else Path(data_dir)

    def __repr__(self) -> str:
        return f"ExampleDataStore({sorted(self.registry)}, data_dir={str(self.data_dir)!r})"

    def __getitem__(self, name: str) -> Path:
        return self.fetch(name)

    def __iter__(self) -> Iterator[str]:
        return iter(self.registry)

    def __len__(self) -> int:
        return len(self.registry)

    def __contains__(self, name) -> bool:
        return name in self.registry

    @property
    def data_dir(self) -> Path:
        """The folder the files are read from and downloaded to."""
        if self._data_dir is not None:
            return self._data_dir
        if os.environ.get(DATA_DIR_ENV):
            return env_folder(DATA_DIR_ENV)
        return Path(_pooch().os_cache("rbm_nb"))

    @property
    def _chosen_folder(self) -> bool:
        return self._data_dir is not None or bool(os.environ.get(DATA_DIR_ENV))

    def _entry(self, name: str) -> tuple[str, str]:
        if name not in self.registry:
            raise KeyError(
                f"{name!r} is not an example dataset; choose one of {sorted(self.registry)}"
            )
        return self.registry[name]

    def path(self, name: str) -> Path:
        """Where ``name`` is (or would be) stored locally; no download."""
        return self.data_dir / self._entry(name)[0]

    def is_available(self, name: str) -> bool:
        """Whether ``name`` is stored locally with the right sha256; no download."""
        path = self.path(name)
        return path.is_file() and sha256(path) == self._entry(name)[1]

    def fetch(self, name: str) -> Path:
        """Local path of ``name``, downloaded first if it is not there.

        Raises
        ------
        KeyError
            If ``name`` is not in the registry.
        ExampleDataUnavailable
            If the file is not there (or has the wrong sha256) and cannot be
            downloaded, or the download does not match its sha256.
        """
        filename, expected = self._entry(name)
        folder = self.data_dir
        path = folder / filename
        if path.is_file():
            actual = sha256(path)
            if actual == expected:
                return path
            if self._chosen_folder:
                raise ExampleDataUnavailable(
                    f"{path} is not the example file {name!r}: its sha256 is {actual}, expected "
                    f"{expected}. It was not used. Replace it with the right file, or delete it "
                    "to have it downloaded again."
                )
            path.unlink()  # a damaged cache entry: drop it, then download afresh
        return self._download(name, filename, expected, folder)

    def _download(self, name: str, filename: str, expected: str, folder: Path) -> Path:
        pooch = _pooch()
        import requests

        url = self.base_url + filename
        bar = download_bar(filename)
        downloader = pooch.HTTPDownloader(progressbar=bar, timeout=self.timeout)
        # pooch logs "Downloading data from ..." even when the connection then
        # fails (offline); the bar shows a real download, our errors a failed one
        logger = pooch.get_logger()
        level = logger.level
        logger.setLevel("WARNING")
        made = _first_missing(folder)  # pooch creates the folder: undone on failure
        try:
            fetched = pooch.retrieve(
                url,
                known_hash=f"sha256:{expected}",
                fname=filename,
                path=folder,
                downloader=downloader,
            )
        except requests.RequestException as err:
            _remove_made_folders(folder, made)
            raise ExampleDataUnavailable(
                f"The example file {filename!r} is not in {folder} and could not be downloaded "
                f"from {url} ({_reason(err)}). {_what_to_do(name, filename, expected)}"
            ) from err
        except ValueError as err:  # pooch's hash check of the download
            _remove_made_folders(folder, made)
            raise ExampleDataUnavailable(
                f"The download of {url} does not have the registered sha256 {expected}, so it "
                f"was discarded. {_what_to_do(name, filename, expected)}"
            ) from err
        except OSError as err:
            _remove_made_folders(folder, made)
            raise ExampleDataUnavailable(
                f"Could not store {filename!r} in {folder} ({err}). Set {DATA_DIR_ENV} to a "
                "writable folder."
            ) from err
        finally:
            logger.setLevel(level)
            if bar is not False:
                bar.close()
        return Path(fetched)


def _first_missing(folder: Path) -> Path | None:
    """The outermost folder of ``folder``'s path that does not exist yet, if any."""
    missing = None
    for candidate in (folder, *folder.parents):
        if candidate.exists():
            break
        missing = candidate
    return missing


def _remove_made_folders(folder: Path, outermost: Path | None) -> None:
    """Remove the (empty) folders a failed download made, up to ``outermost``."""
    if outermost is None:
        return
    for candidate in (folder, *folder.parents):
        try:
            candidate.rmdir()  # only if empty: never anything with a file in it
        except OSError:
            return
        if candidate == outermost:
            return


def sha256(path: Path) -> str:
    """Hex sha256 of a file's bytes."""
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def _reason(err) -> str:
    import requests

    if isinstance(err, requests.Timeout):
        return "the connection timed out"
    if isinstance(err, requests.ConnectionError):
        host = getattr(getattr(err, "request", None), "url", None) or "the server"
        return f"could not connect to {host.split('/')[2] if '://' in host else host}"
    if isinstance(err, requests.HTTPError) and err.response is not None:
        return f"HTTP {err.response.status_code} {err.response.reason}"
    return f"{type(err).__name__}: {err}"


def _what_to_do(name: str, filename: str, expected: str) -> str:
    return (
        f"To work offline, put {filename} (sha256 {expected}) into a folder and set the "
        f"environment variable {DATA_DIR_ENV} to that folder, or use the synthetic recording: "
        f"rbm_nb.data.load_example({name!r}, source='synthetic')."
    )


example_data = ExampleDataStore()
