"""The viewer server for real: HTTP, websocket clients, what reaches them, cleanup."""

from __future__ import annotations

import errno
import json
import socket
import subprocess
import sys
import threading
import urllib.error
import urllib.request

import numpy as np
import pytest
import umsgpack
import websocket

import rbm_nb as rbm
from rbm_nb.scene import Scene, ViewerServer, commands, get_server, shutdown_server
from rbm_nb.scene.commands import pose_matrix
from rbm_nb.scene.server import meshcat_js_path


@pytest.fixture(autouse=True)
def no_server_left_behind():
    yield
    shutdown_server()
    assert not [
        t
        for t in threading.enumerate()
        if t.name.startswith("rbm_nb-viewer") and t.is_alive()
    ]


@pytest.fixture
def server():
    srv = ViewerServer()
    yield srv
    srv.close()


class ViewerClient:
    """A websocket client reading what a browser would get."""

    def __init__(self, url: str):
        self.ws = websocket.create_connection(url, timeout=10)
        self.messages: list = []

    def read(self, until=None, quiet: float = 0.3, timeout: float = 10.0) -> list:
        """Read until ``until(messages)`` holds, or nothing came for ``quiet`` s."""
        got = []
        self.ws.settimeout(quiet if until is None else timeout)
        while True:
            try:
                data = self.ws.recv()
            except websocket.WebSocketTimeoutException:
                if until is not None:
                    raise AssertionError(
                        f"expected messages did not arrive; got {got}"
                    ) from None
                return got
            message = (
                umsgpack.unpackb(data) if isinstance(data, bytes) else json.loads(data)
            )
            got.append(message)
            self.messages.append(message)
            if until is not None and until(got):
                return got

    def close(self):
        self.ws.close()


@pytest.fixture
def client_factory():
    clients = []

    def connect(url):
        client = ViewerClient(url)
        clients.append(client)
        return client

    yield connect
    for client in clients:
        client.close()


@pytest.fixture
def moving():
    rbm.register_frame("world")
    ts = np.arange(11) * 0.1
    rbm.register_frame(
        "body",
        parent="world",
        timestamps=ts,
        translation=np.c_[np.arange(11.0), np.zeros(11), np.zeros(11)],
    )
    rbm.register_frame("eye", parent="body", translation=(0.1, 0.0, 0.2))
    return ts


def ws_url(http_url: str) -> str:
    return http_url.replace("http://", "ws://") + "ws"


def get(url: str):
    request = urllib.request.Request(url)
    opener = urllib.request.build_opener(NoRedirect)
    return opener.open(request, timeout=10)


class NoRedirect(urllib.request.HTTPRedirectHandler):
    def redirect_request(self, *args, **kwargs):
        return None


# -- HTTP ---------------------------------------------------------------------------
def test_viewer_page_uses_relative_urls_only(server):
    server.add_channel("demo")
    page = get(server.channel_url("demo")).read().decode()
    assert '<script src="../static/main.min.js">' in page
    assert '<script src="../static/viewer.js">' in page
    assert "ws://" not in page and "http://" not in page
    js = get(server.url + "static/viewer.js").read().decode()
    assert 'new URL("ws", window.location.href)' in js
    assert 'window.location.protocol === "https:" ? "wss:" : "ws:"' in js
    bundle = get(server.url + "static/main.min.js").read()
    assert bundle == meshcat_js_path().read_bytes()
    assert "demo/" in get(server.url).read().decode()


def test_channel_without_slash_redirects_relatively(server):
    server.add_channel("demo")
    with pytest.raises(urllib.error.HTTPError) as err:
        get(server.url + "demo")
    assert err.value.code == 302
    assert err.value.headers["Location"] == "demo/"


def test_unknown_channel_and_file(server):
    for path in ("nope/", "static/other.js"):
        with pytest.raises(urllib.error.HTTPError) as err:
            get(server.url + path)
        assert err.value.code == 404


def test_server_binds_loopback_only(server):
    assert server.host == "127.0.0.1"
    assert server.url == f"http://127.0.0.1:{server.port}/"
    assert server._sockets[0].getsockname()[0] == "127.0.0.1"


# -- what the browser gets ----------------------------------------------------------
def test_new_viewer_gets_the_whole_scene_then_updates(moving, client_factory):
    scene = Scene("world")
    frame = scene.add_frame("body")
    path = scene.add_path("body", color="#ff00ff")
    client = client_factory(ws_url(scene.url))
    first = client.read()
    assert first[0] == {"type": "rbm_reset"}
    objects = {m["path"] for m in first if m.get("type") == "set_object"}
    assert objects == {frame.geom_path, path.geom_path}
    poses = {m["path"]: m["matrix"] for m in first if m.get("type") == "set_transform"}
    assert poses[frame.pose_path][12] == 0.0
    scene.set_time(0.42)
    update = client.read(
        until=lambda got: any(m.get("path") == frame.pose_path for m in got)
    )
    matrix = (
        np.asarray(
            next(m for m in update if m.get("path") == frame.pose_path)["matrix"]
        )
        .reshape(4, 4)
        .T
    )
    np.testing.assert_allclose(matrix, pose_matrix([4.0, 0.0, 0.0], [1, 0, 0, 0]))
    stats = scene.server.stats(scene.name)
    assert stats["clients"] == 1 and frame.geom_path in stats["paths"]
    scene.close()


def test_late_viewer_sees_the_current_time(moving, client_factory):
    scene = Scene("world")
    frame = scene.add_frame("body")
    assert not scene.server.closed  # shown before anything moves
    scene.set_time(0.7)
    client = client_factory(ws_url(scene.url))
    got = client.read()
    poses = [
        m
        for m in got
        if m.get("type") == "set_transform" and m["path"] == frame.pose_path
    ]
    assert len(poses) == 1 and poses[0]["matrix"][12] == 7.0
    scene.close()


def test_player_steps_reach_the_viewer(moving, client_factory):
    scene = Scene("world")
    frame = scene.add_frame("body")
    vectors = scene.add_vectors("eye", (1, 0, 0))
    player = scene.player(threaded=False)
    client = client_factory(ws_url(scene.url))
    client.read()
    player.seek(9)
    got = client.read(
        until=lambda g: (
            {m.get("path") for m in g} >= {frame.pose_path, vectors.pose_path}
        )
    )
    x = {m["path"]: m["matrix"][12] for m in got if m.get("type") == "set_transform"}
    assert x[frame.pose_path] == 9.0 and x[vectors.pose_path] == pytest.approx(9.1)
    player.close()
    scene.close()


def test_two_viewers_both_get_updates(moving, client_factory):
    scene = Scene("world")
    frame = scene.add_frame("body")
    a = client_factory(ws_url(scene.url))
    b = client_factory(ws_url(scene.url))
    a.read()
    b.read()
    scene.set_time(0.3)
    for client in (a, b):
        got = client.read(
            until=lambda g: any(m.get("path") == frame.pose_path for m in g)
        )
        assert got[-1]["matrix"][12] == 3.0
    scene.close()


def test_pending_transforms_are_coalesced_not_queued(server, client_factory):
    server.add_channel("raw")
    client = client_factory(ws_url(server.channel_url("raw")))
    client.read()
    burst = [
        commands.set_transform("/rbm/a", pose_matrix([i, 0, 0], [1, 0, 0, 0]))
        for i in range(500)
    ]
    burst.append(commands.set_transform("/rbm/b", np.eye(4)))
    server.send("raw", burst)
    got = client.read()
    assert [(m["path"], m["matrix"][12]) for m in got] == [
        ("/rbm/a", 499.0),
        ("/rbm/b", 0.0),
    ]


def test_coalescing_keeps_order_around_deletes(server, client_factory):
    server.add_channel("raw")
    client = client_factory(ws_url(server.channel_url("raw")))
    client.read()
    batch = [
        commands.set_transform("/rbm/a", pose_matrix([i, 0, 0], [1, 0, 0, 0]))
        for i in range(3)
    ]
    batch.append(commands.delete("/rbm/a"))
    batch += [
        commands.set_transform("/rbm/a", pose_matrix([i, 0, 0], [1, 0, 0, 0]))
        for i in (10, 11)
    ]
    server.send("raw", batch)
    got = client.read()
    assert [(m["type"], m.get("matrix", [0] * 16)[12]) for m in got] == [
        ("set_transform", 2.0),
        ("delete", 0),
        ("set_transform", 11.0),
    ]


def test_closing_a_scene_disconnects_its_viewers(moving, client_factory):
    scene = Scene("world")
    scene.add_frame("body")
    url = scene.url
    client = client_factory(ws_url(url))
    client.read()
    scene.close()
    client.ws.settimeout(10)
    opcode, data = client.ws.recv_data(control_frame=True)
    assert opcode == websocket.ABNF.OPCODE_CLOSE
    assert int.from_bytes(data[:2], "big") == 4000
    with pytest.raises(urllib.error.HTTPError):
        get(url)


# -- life cycle and bad input ---------------------------------------------------------
def test_port_already_taken():
    blocker = socket.socket()
    blocker.bind(("127.0.0.1", 0))
    blocker.listen()
    port = blocker.getsockname()[1]
    try:
        with pytest.raises(OSError, match=f"127.0.0.1:{port} is already in use") as err:
            ViewerServer(port=port)
        assert err.value.errno == errno.EADDRINUSE
    finally:
        blocker.close()


@pytest.mark.parametrize("port", [-1, 70000, "7000", True])
def test_bad_port(port):
    with pytest.raises(ValueError, match="port"):
        ViewerServer(port=port)


def test_close_is_idempotent_and_frees_everything():
    srv = ViewerServer()
    port = srv.port
    srv.add_channel("x")
    srv.close()
    srv.close()
    assert srv.closed and not srv._thread.is_alive()
    again = socket.socket()
    again.bind(("127.0.0.1", port))  # the port is free again
    again.close()
    with pytest.raises(RuntimeError, match="closed"):
        srv.send("x", [])
    with pytest.raises(RuntimeError, match="closed"):
        srv.add_channel("y")
    srv.remove_channel("x")  # no-op once closed


def test_bad_channel_name(server):
    with pytest.raises(ValueError, match="channel names"):
        server.add_channel("a/b")


def test_one_shared_server_per_kernel():
    first = get_server()
    assert get_server() is first and get_server(first.port) is first
    with pytest.raises(ValueError, match="already runs on port"):
        get_server(port=first.port + 1 if first.port < 65535 else 1)
    shutdown_server()
    shutdown_server()
    assert first.closed
    second = get_server()
    assert second is not first and not second.closed


def test_scene_reattaches_after_server_restart(moving, client_factory):
    scene = Scene("world")
    frame = scene.add_frame("body")
    old = scene.server
    shutdown_server()
    assert old.closed
    client = client_factory(ws_url(scene.url))  # a new server, same scene
    got = client.read()
    assert any(m.get("path") == frame.geom_path for m in got)
    scene.close()


def test_nothing_keeps_running_after_the_interpreter_exits():
    code = (
        "import rbm_nb as rbm\n"
        "from rbm_nb.scene import Scene\n"
        "rbm.register_frame('world')\n"
        "scene = Scene('world')\n"
        "print(scene.server.port, flush=True)\n"  # started, never closed
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    port = int(done.stdout.split()[-1])
    probe = socket.socket()
    probe.bind(("127.0.0.1", port))  # the port was released with the process
    probe.close()
