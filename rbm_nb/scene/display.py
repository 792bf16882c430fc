"""The live viewer as notebook output: an iframe whose address fits the notebook.

The kernel does not know how the browser reaches it. On a notebook opened
over http on the loopback (a local Jupyter), the viewer server is reachable
directly at ``http://127.0.0.1:<port>/``; anywhere else (Binder, JupyterHub,
https, another machine) it must go through jupyter-server-proxy at
``<base_url>proxy/<port>/``. A few lines of script in the output decide, in
the browser, from ``window.location`` and JupyterLab's page config.
"""

from __future__ import annotations

import html
import os
import uuid

MODES = {"always": "proxy", "never": "direct", "auto": "auto"}


def proxy_mode(proxy: bool | None) -> str:
    """``proxy``, ``direct`` or ``auto`` from the argument or ``$RBM_NB_VIEWER_PROXY``."""
    if proxy is not None:
        return "proxy" if proxy else "direct"
    setting = os.environ.get("RBM_NB_VIEWER_PROXY", "auto").strip().lower()
    if setting not in MODES:
        raise ValueError(
            f"RBM_NB_VIEWER_PROXY must be one of {sorted(MODES)}, got {setting!r}"
        )
    return MODES[setting]


def viewer_html(
    port: int,
    channel: str,
    direct_url: str,
    height: int = 480,
    proxy: bool | None = None,
) -> str:
    """HTML of an iframe showing scene ``channel`` of the server on ``port``.

    The iframe gets its address from the script (no request goes to a URL
    that the browser may not reach); the link below it is the direct URL for
    when scripts do not run.
    """
    mode = proxy_mode(proxy)
    frame_id = f"rbm-view-{channel}-{uuid.uuid4().hex[:8]}"
    direct = html.escape(direct_url)
    title = html.escape(f"rbm_nb scene {channel}")
    return f"""<div class="rbm-scene" style="height:{int(height)}px;width:100%;resize:vertical;overflow:hidden">
<iframe id="{frame_id}" data-port="{int(port)}" data-channel="{channel}" data-direct="{direct}"
 style="width:100%;height:100%;border:none" title="{title}"></iframe></div>
<script>(function () {{
  var mode = "{mode}", port = {int(port)}, channel = "{channel}";
  var frame = document.getElementById("{frame_id}");
  if (!frame) {{ return; }}
  var base = "/";
  var config = document.getElementById("jupyter-config-data");
  if (config) {{ try {{ base = JSON.parse(config.textContent).baseUrl || "/"; }} catch (e) {{}} }}
  var loopback = ["localhost", "127.0.0.1", "[::1]", "::1"].indexOf(window.location.hostname) >= 0;
  var viaProxy = mode === "proxy" || (mode === "auto" && !(loopback && window.location.protocol === "http:"));
  frame.src = viaProxy ? base.replace(/\\/?$/, "/") + "proxy/" + port + "/" + channel + "/" : frame.dataset.direct;
}})();</script>
<noscript><a href="{direct}">open the rbm_nb viewer</a></noscript>"""
