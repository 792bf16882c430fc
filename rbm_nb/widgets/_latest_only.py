"""Run requests off the kernel's message loop, the newest of each view only.

A zoom or a pan sends the kernel a request per step; only the last one's
answer will be drawn. The kernel handles comm messages one at a time on its
main thread, so it cannot see a newer request while it computes an older one.
Here the message handler only records the request and returns; one worker
thread computes, and a request is cancelled as soon as a newer one from the
same view arrives: skipped if not started, stopped at its next check (the job
asks ``cancelled()`` between steps) if running. Its answer is never sent.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor

from ._decimate import Cancelled

#: job(cancelled) -> result, or raises Cancelled
Job = Callable[[Callable[[], bool]], object]


class LatestOnly:
    """One worker thread; per view, a request cancels the ones before it."""

    def __init__(self, name: str):
        self._name = name
        self._lock = threading.Lock()
        self._newest: dict[str, int] = {}
        self._count = 0
        self._pool: ThreadPoolExecutor | None = None
        #: requests answered / cancelled (before or while running)
        self.answered = 0
        self.cancelled = 0

    def submit(self, view: str, job: Job, done: Callable[[object], None]) -> Future:
        """Run ``job`` for ``view``, then ``done(result)`` unless cancelled."""
        with self._lock:
            self._count += 1
            ticket = self._newest[view] = self._count
            if self._pool is None:
                self._pool = ThreadPoolExecutor(1, thread_name_prefix=self._name)
            pool = self._pool

        def stale() -> bool:
            return self._newest.get(view) != ticket

        def run():
            try:
                if stale():
                    raise Cancelled
                result = job(stale)
                if stale():
                    raise Cancelled
            except Cancelled:
                with self._lock:
                    self.cancelled += 1
                return None
            done(result)
            with self._lock:
                self.answered += 1
            return result

        return pool.submit(run)

    def close(self) -> None:
        """Cancel what is queued and let the worker end (does not wait)."""
        with self._lock:
            self._newest.clear()
            pool, self._pool = self._pool, None
        if pool is not None:
            pool.shutdown(wait=False, cancel_futures=True)
