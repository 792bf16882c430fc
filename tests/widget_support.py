"""One stand-in for a kernel comm, shared by every widget test.

Widgets built outside a kernel need a comm to open; ``RecordingComm`` takes
its place (the ``recording_comm`` fixture in ``conftest.py`` installs it) and
keeps what the kernel would have sent to the browser, so tests can check the
wire format, and it can play the browser's side back to the widget.
"""

from __future__ import annotations

import uuid


class RecordingComm:
    """A comm that records what the widget sends and replays browser messages.

    Attributes
    ----------
    comm_id : str
        Unique per comm, like a kernel's.
    opened : tuple
        ``(data, buffers)`` the widget opened the comm with: its first state.
    sent : list of tuple
        ``(data, buffers)`` per message sent after opening; buffers as bytes.
    handlers : list of callable
        What the widget registered with ``on_msg``.
    """

    kernel = "Truthy"  # ipywidgets only checks that there is one

    def __init__(self, *args, data=None, buffers=None, **kwargs):
        self.comm_id = uuid.uuid4().hex
        self.opened = (data, buffers)
        self.sent: list[tuple[dict | None, list[bytes]]] = []
        self.handlers: list = []

    @property
    def messages(self) -> list[dict | None]:
        """The data of each message sent, without its buffers."""
        return [data for data, _ in self.sent]

    def open(self, *args, **kwargs):
        pass

    def on_msg(self, callback):
        self.handlers.append(callback)

    def send(self, data=None, metadata=None, buffers=None):
        # copied: the widget may reuse the memory it handed over
        self.sent.append((data, [bytes(b) for b in buffers or []]))

    def close(self, *args, **kwargs):
        pass

    def _deliver(self, data: dict) -> None:
        msg = {"content": {"data": data}, "buffers": []}
        for handler in self.handlers:
            handler(msg)

    def receive_state(self, state: dict) -> None:
        """What the browser sends when it updates traits."""
        self._deliver({"method": "update", "state": state, "buffer_paths": []})

    def receive(self, content: dict) -> None:
        """What the browser sends as a custom message (``model.send``)."""
        self._deliver({"method": "custom", "content": content})
