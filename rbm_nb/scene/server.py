"""The meshcat viewer server: one per kernel, in a background thread.

meshcat's own server is a separate process reached through ZeroMQ, and its
``Visualizer.close()`` raises. This module replaces it with a small tornado
application running on its own asyncio loop in a daemon thread of the kernel:

* ``/static/main.min.js`` is meshcat's bundled viewer, ``/static/viewer.js``
  our glue; ``/<channel>/`` is the viewer page of one scene and
  ``/<channel>/ws`` its websocket, both found relative to the page's own URL so
  that the page works unchanged behind jupyter-server-proxy (``/proxy/<port>/``
  prefixes, https).
* Each channel keeps the current scene tree so that a browser connecting late
  (or reconnecting) is sent the whole scene.
* Transforms and properties are coalesced per path: when a browser (or the
  network) is slower than the publisher, it gets the latest pose of every
  object, never a backlog of stale ones.

The server binds to 127.0.0.1 only. ``close()`` is idempotent and an atexit
hook closes the shared server, so nothing is left listening after the kernel
exits (the thread dies with the process in any case).
"""

from __future__ import annotations

import asyncio
import atexit
import errno
import itertools
import json
import os
import threading
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import tornado.httpserver
import tornado.netutil
import tornado.web
import tornado.websocket

VIEWER_DIR = Path(__file__).resolve().parent / "viewer"
CHANNEL_PATTERN = r"[A-Za-z0-9_\-]+"


def meshcat_js_path() -> Path:
    """Path of meshcat's bundled ``main.min.js``."""
    import importlib.util

    spec = importlib.util.find_spec("meshcat")
    if spec is None or not spec.submodule_search_locations:
        raise ModuleNotFoundError(
            "the notebook layer needs meshcat: pip install 'rbm_nb[notebook]'"
        )
    package = Path(list(spec.submodule_search_locations)[0])
    path = package / "viewer" / "dist" / "main.min.js"
    if not path.is_file():
        raise FileNotFoundError(
            f"meshcat's viewer bundle is missing at {path}; reinstall meshcat (pip install meshcat)"
        )
    return path


@dataclass(frozen=True)
class Message:
    """One command for the viewer.

    Attributes
    ----------
    op : str
        ``set_object``, ``set_transform``, ``set_property``, ``delete``,
        ``set_animation`` (msgpack payloads) or ``json`` (a text message for
        our viewer page, e.g. camera placement).
    path : str
        Scene path, e.g. ``/rbm/root/frame-head``; for ``json`` a key.
    data : bytes or str
        The lowered command.
    prop : str, optional
        Property name for ``set_property``.
    """

    op: str
    path: str
    data: bytes | str
    prop: str = ""

    @property
    def coalescable(self) -> bool:
        return self.op in ("set_transform", "set_property", "json")

    @property
    def key(self) -> tuple:
        return (self.op, self.path, self.prop)


_unique = itertools.count()


class _Queue:
    """Ordered messages where a newer transform/property replaces an unsent one.

    Segments keep the order around non-coalescable commands: a transform sent
    after a ``delete`` must not move in front of it.
    """

    def __init__(self):
        self.segments: list[dict] = []

    def push(self, message: Message) -> None:
        if message.coalescable:
            if not self.segments or "_sealed" in self.segments[-1]:
                self.segments.append({})
            self.segments[-1][message.key] = message
        else:
            self.segments.append({"_sealed": True, ("unique", next(_unique)): message})

    def pop_all(self) -> list[Message]:
        out = []
        for segment in self.segments:
            out.extend(m for k, m in segment.items() if k != "_sealed")
        self.segments = []
        return out

    def __bool__(self) -> bool:
        return bool(self.segments)


class _Channel:
    """State of one scene on the server thread: its tree and its browsers."""

    def __init__(self, name: str):
        self.name = name
        self.objects: dict[str, Message] = {}
        self.properties: dict[tuple, Message] = {}
        self.transforms: dict[str, Message] = {}
        self.extras: dict[str, Message] = {}
        self.animation: Message | None = None
        self.clients: set[_Client] = set()
        self.received = 0

    def apply(self, message: Message) -> None:
        self.received += 1
        op, path = message.op, message.path
        if op == "set_object":
            self.objects.pop(path, None)
            self.objects[path] = message
            for key in [k for k in self.properties if k[0] == path]:
                del self.properties[key]
        elif op == "set_transform":
            self.transforms[path] = message
        elif op == "set_property":
            self.properties[(path, message.prop)] = message
        elif op == "set_animation":
            self.animation = message
        elif op == "json":
            self.extras[path] = message
        elif op == "delete":
            prefix = path.rstrip("/") + "/"

            def gone(p: str) -> bool:
                return p == path or p.startswith(prefix)

            for table in (self.objects, self.transforms):
                for key in [k for k in table if gone(k)]:
                    del table[key]
            for key in [k for k in self.properties if gone(k[0])]:
                del self.properties[key]

    def snapshot(self) -> list[Message]:
        out = [Message("json", "reset", json.dumps({"type": "rbm_reset"}))]
        out += list(self.objects.values())
        out += list(self.properties.values())
        out += list(self.transforms.values())
        if self.animation is not None:
            out.append(self.animation)
        out += list(self.extras.values())
        return out


class _Client:
    """One connected browser with its own coalescing send queue."""

    def __init__(self, handler: tornado.websocket.WebSocketHandler):
        self.handler = handler
        self.queue = _Queue()
        self.draining = False
        self.sent = 0

    def push(self, messages: Iterable[Message]) -> None:
        for message in messages:
            self.queue.push(message)
        if not self.draining:
            self.draining = True
            asyncio.ensure_future(self._drain())

    async def _drain(self) -> None:
        try:
            while self.queue:
                last = None
                for message in self.queue.pop_all():
                    binary = isinstance(message.data, bytes)
                    last = self.handler.write_message(message.data, binary=binary)
                    self.sent += 1
                if last is not None:
                    # Back-pressure: while this write is pending, new poses
                    # collect in the queue and replace each other.
                    await last
        except tornado.websocket.WebSocketClosedError:
            self.queue = _Queue()
        finally:
            self.draining = False


class _ViewerPage(tornado.web.RequestHandler):
    def initialize(self, server: ViewerServer):
        self.server = server

    def get(self, channel: str, slash: str = ""):
        if channel not in self.server._channels:
            raise tornado.web.HTTPError(
                404, reason=f"no scene {channel!r} on this server"
            )
        if not slash:
            # relative, so that it survives path prefixes of proxies
            self.redirect(f"{channel}/", permanent=False)
            return
        self.set_header("Content-Type", "text/html; charset=utf-8")
        self.set_header("Cache-Control", "no-store")
        self.write((VIEWER_DIR / "index.html").read_bytes())


class _Index(tornado.web.RequestHandler):
    def initialize(self, server: ViewerServer):
        self.server = server

    def get(self):
        links = "".join(
            f'<li><a href="{name}/">{name}</a></li>'
            for name in sorted(self.server._channels)
        )
        self.write(
            f"<!DOCTYPE html><html><body><h1>rbm_nb scenes</h1><ul>{links}</ul></body></html>"
        )


class _Static(tornado.web.RequestHandler):
    def initialize(self, files: dict[str, Path]):
        self.files = files

    def get(self, name: str):
        path = self.files.get(name)
        if path is None:
            raise tornado.web.HTTPError(404)
        self.set_header("Content-Type", "application/javascript; charset=utf-8")
        self.set_header("Cache-Control", "max-age=3600")
        self.write(path.read_bytes())


class _Socket(tornado.websocket.WebSocketHandler):
    def initialize(self, server: ViewerServer):
        self.server = server
        self.client: _Client | None = None
        self.channel: _Channel | None = None

    def open(self, channel: str):
        state = self.server._channels.get(channel)
        if state is None:
            self.close(code=4004, reason=f"no scene {channel!r}")
            return
        self.set_nodelay(True)
        self.channel = state
        self.client = _Client(self)
        state.clients.add(self.client)
        self.client.push(state.snapshot())

    def on_message(self, message):
        # The viewer only talks back for image captures; nothing to do.
        pass

    def on_close(self):
        if self.channel is not None and self.client is not None:
            self.channel.clients.discard(self.client)


class ViewerServer:
    """A meshcat viewer server on 127.0.0.1 in a daemon thread.

    Parameters
    ----------
    port : int, default 0
        TCP port; 0 picks a free one.
    host : str, default "127.0.0.1"
        Interface to bind. Keep the loopback default unless you know who can
        reach the machine.

    Raises
    ------
    OSError
        If the port is already in use.
    """

    def __init__(self, port: int = 0, host: str = "127.0.0.1"):
        if (
            not isinstance(port, int)
            or isinstance(port, bool)
            or not 0 <= port <= 65535
        ):
            raise ValueError(f"port must be an integer in [0, 65535], got {port!r}")
        self.host = host
        try:
            self._sockets = tornado.netutil.bind_sockets(
                port, address=host, reuse_port=False
            )
        except OSError as err:
            if err.errno == errno.EADDRINUSE:
                raise OSError(
                    errno.EADDRINUSE,
                    f"cannot start the meshcat viewer server: {host}:{port} is already in use "
                    "(pass port=0 to pick a free port)",
                ) from err
            raise
        self.port = self._sockets[0].getsockname()[1]
        self._channels: dict[str, _Channel] = {}
        self._inbox: dict[str, _Queue] = {}
        self._inbox_lock = threading.Lock()
        self._flush_scheduled = False
        self._closed = False
        self._ready = threading.Event()
        self._startup_error: BaseException | None = None
        self._loop: asyncio.AbstractEventLoop | None = None
        self._thread = threading.Thread(
            target=self._run, name=f"rbm_nb-viewer-{self.port}", daemon=True
        )
        self._thread.start()
        started = self._ready.wait(timeout=60)
        if self._startup_error is not None or not started:
            self.close()
            raise RuntimeError(
                "the meshcat viewer server failed to start"
            ) from self._startup_error

    # -- public API -----------------------------------------------------------
    @property
    def url(self) -> str:
        """Base URL of the server, with a trailing slash."""
        return f"http://{self.host}:{self.port}/"

    @property
    def closed(self) -> bool:
        return self._closed

    def channel_url(self, channel: str) -> str:
        """URL of the viewer page of ``channel``."""
        return f"{self.url}{channel}/"

    def add_channel(self, channel: str) -> None:
        """Create an empty scene channel (idempotent)."""
        self._check_open()
        if not _valid_channel(channel):
            raise ValueError(
                f"channel names are letters, digits, '-' and '_', got {channel!r}"
            )
        self._call(self._add_channel, channel)

    def remove_channel(self, channel: str) -> None:
        """Forget a channel and disconnect its browsers (no-op once closed)."""
        if self._closed:
            return
        self._call(self._remove_channel, channel)

    def send(self, channel: str, messages: Iterable[Message]) -> None:
        """Queue messages for ``channel``; thread-safe and non-blocking.

        Transforms and properties of a path still waiting to be sent are
        replaced by newer ones.
        """
        self._check_open()
        with self._inbox_lock:
            queue = self._inbox.setdefault(channel, _Queue())
            for message in messages:
                queue.push(message)
            if self._flush_scheduled:
                return
            self._flush_scheduled = True
        try:
            self._loop.call_soon_threadsafe(self._flush)
        except RuntimeError:  # loop closed under our feet during shutdown
            pass

    def stats(self, channel: str) -> dict:
        """Counters for tests and diagnostics: messages applied, clients connected."""
        self._check_open()
        return self._call(self._stats, channel)

    def close(self) -> None:
        """Stop the server and its thread; safe to call more than once."""
        if self._closed:
            return
        self._closed = True
        loop = self._loop
        if loop is not None and self._thread.is_alive():
            try:
                loop.call_soon_threadsafe(loop.stop)
            except RuntimeError:
                pass
            self._thread.join(timeout=10)
        for sock in self._sockets:
            try:
                sock.close()
            except OSError:
                pass

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def __repr__(self) -> str:
        state = "closed" if self._closed else self.url
        return f"<ViewerServer {state}>"

    # -- server thread --------------------------------------------------------
    def _check_open(self) -> None:
        if self._closed:
            raise RuntimeError("the meshcat viewer server is closed")

    def _call(self, func, *args, timeout: float = 10.0):
        """Run ``func(*args)`` on the server thread and wait for its result."""
        if threading.current_thread() is self._thread:
            return func(*args)
        done = threading.Event()
        box: dict = {}

        def run():
            try:
                box["value"] = func(*args)
            except BaseException as err:  # handed back to the caller
                box["error"] = err
            finally:
                done.set()

        self._loop.call_soon_threadsafe(run)
        if not done.wait(timeout):
            raise TimeoutError("the meshcat viewer server did not answer")
        if "error" in box:
            raise box["error"]
        return box.get("value")

    def _run(self) -> None:
        loop = asyncio.new_event_loop()
        asyncio.set_event_loop(loop)
        try:
            http = loop.run_until_complete(self._start())
        except BaseException as err:
            self._startup_error = err
            self._ready.set()
            loop.close()
            return
        self._loop = loop
        self._ready.set()
        try:
            loop.run_forever()
        finally:
            http.stop()
            for channel in self._channels.values():
                for client in list(channel.clients):
                    client.handler.close()
            try:
                loop.run_until_complete(
                    asyncio.wait_for(http.close_all_connections(), 5)
                )
            except (asyncio.TimeoutError, Exception):
                pass
            pending = [t for t in asyncio.all_tasks(loop) if not t.done()]
            for task in pending:
                task.cancel()
            if pending:
                loop.run_until_complete(
                    asyncio.gather(*pending, return_exceptions=True)
                )
            loop.close()

    async def _start(self) -> tornado.httpserver.HTTPServer:
        files = {
            "main.min.js": meshcat_js_path(),
            "viewer.js": VIEWER_DIR / "viewer.js",
        }
        app = tornado.web.Application(
            [
                (r"/", _Index, {"server": self}),
                (r"/static/([A-Za-z0-9_.\-]+)", _Static, {"files": files}),
                (rf"/({CHANNEL_PATTERN})/ws", _Socket, {"server": self}),
                (rf"/({CHANNEL_PATTERN})(/?)", _ViewerPage, {"server": self}),
            ],
            websocket_max_message_size=64 * 1024 * 1024,
        )
        http = tornado.httpserver.HTTPServer(app)
        http.add_sockets(self._sockets)
        return http

    def _add_channel(self, name: str) -> None:
        self._channels.setdefault(name, _Channel(name))

    def _remove_channel(self, name: str) -> None:
        channel = self._channels.pop(name, None)
        with self._inbox_lock:
            self._inbox.pop(name, None)
        if channel is not None:
            for client in list(channel.clients):
                client.handler.close(code=4000, reason="scene closed")

    def _stats(self, name: str) -> dict:
        channel = self._channels.get(name)
        if channel is None:
            raise ValueError(f"no channel {name!r} on this server")
        return {
            "received": channel.received,
            "clients": len(channel.clients),
            "sent": sum(c.sent for c in channel.clients),
            "paths": sorted(channel.objects),
        }

    def _flush(self) -> None:
        with self._inbox_lock:
            inbox, self._inbox = self._inbox, {}
            self._flush_scheduled = False
        for name, queue in inbox.items():
            channel = self._channels.get(name)
            if channel is None:
                continue
            messages = queue.pop_all()
            for message in messages:
                channel.apply(message)
            for client in list(channel.clients):
                client.push(messages)


def _valid_channel(name: str) -> bool:
    import re

    return isinstance(name, str) and re.fullmatch(CHANNEL_PATTERN, name) is not None


_shared: ViewerServer | None = None
_shared_lock = threading.Lock()


def get_server(port: int | None = None) -> ViewerServer:
    """The kernel's viewer server, started on first use.

    Parameters
    ----------
    port : int, optional
        Port for the first start; by default ``$RBM_NB_VIEWER_PORT`` or a free
        port. Asking for a different port than the running server's is an
        error: call :func:`shutdown_server` first.
    """
    global _shared
    with _shared_lock:
        if _shared is not None and not _shared.closed:
            if port not in (None, 0, _shared.port):
                raise ValueError(
                    f"the viewer server already runs on port {_shared.port}; "
                    f"call rbm_nb.scene.shutdown_server() before asking for port {port}"
                )
            return _shared
        if port is None:
            port = int(os.environ.get("RBM_NB_VIEWER_PORT", "0") or 0)
        _shared = ViewerServer(port=port)
        return _shared


def shutdown_server() -> None:
    """Close the kernel's viewer server if it runs (idempotent)."""
    global _shared
    with _shared_lock:
        server, _shared = _shared, None
    if server is not None:
        server.close()


atexit.register(shutdown_server)
