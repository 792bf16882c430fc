"""Open saved pages (docs, nbconvert HTML) in chromium with every request off disk refused.

Used by ``tests/project/test_docs.py`` and ``tests/notebook/test_browser_offline.py``:
the pages must draw their widgets from their own files, with no kernel and
no network.
"""

from __future__ import annotations

from contextlib import contextmanager
from pathlib import Path

from browser_support import CHROMIUM, CHROMIUM_ARGS

# what a page's 3D views hold: per view, the number of moving objects and the
# positions of their nodes now (scene.js keeps the view on its root element)
SCENE_STATE_JS = """() => [...document.querySelectorAll('.rbm-scene')].map((el) => {
  const view = el.rbmView;
  if (!view) { return null; }
  const tracks = [...view.store.tracks.values()];
  return {
    commands: view.store.commands.length,
    tracks: tracks.length,
    positions: tracks.map((t) => view.node(t.path).position.toArray()),
  };
})"""


@contextmanager
def offline_page(path: Path, *, width: int = 1280, height: int = 1000):
    """A chromium page showing ``path``; yields (page, refused URLs, console errors)."""
    from playwright.sync_api import sync_playwright

    refused: list[str] = []
    errors: list[str] = []
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=CHROMIUM_ARGS)
        try:
            context = browser.new_context(viewport={"width": width, "height": height})

            def only_disk(route):
                url = route.request.url
                if url.startswith(("file://", "data:", "blob:")):
                    route.continue_()
                else:
                    refused.append(url)
                    route.abort()

            context.route("**/*", only_disk)
            page = context.new_page()
            page.on("pageerror", lambda e: errors.append(str(e)))
            page.goto(path.resolve().as_uri())
            yield page, refused, errors
        finally:
            browser.close()


def wait_for_scene(page, timeout_ms: int = 30000) -> None:
    """Until a 3D view on the page holds content drawn from the saved state."""
    page.wait_for_function(
        """() => [...document.querySelectorAll('.rbm-scene')]
              .some((el) => el.rbmView && el.rbmView.store.commands.length > 0)""",
        timeout=timeout_ms,
    )
