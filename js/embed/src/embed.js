// Jupyter's widget manager for a static page, with anywidget, and no CDN.
//
// nbconvert's HTML and the docs pages carry each notebook's saved widget state
// in <script type="application/vnd.jupyter.widget-state+json"> and a view
// tag per output. @jupyter-widgets/html-manager renders those; by default it
// fetches any widget module it does not know (anywidget) from a CDN. This
// bundle hands it anywidget's module from npm instead, so a page works from
// its own files, offline. rbm_nb's widgets carry their JavaScript in their
// state (anywidget's _esm), so nothing else is needed.
import * as base from "@jupyter-widgets/base";
import { HTMLManager } from "@jupyter-widgets/html-manager/lib/htmlmanager.js";
import { renderWidgets } from "@jupyter-widgets/html-manager/lib/libembed.js";
import { widgetModule } from "anywidget";

const anywidget = widgetModule(base);

function loader(moduleName, moduleVersion) {
  if (moduleName === "anywidget") {
    return Promise.resolve(anywidget);
  }
  return Promise.reject(
    new Error(`widget module ${moduleName}@${moduleVersion} is not bundled with this page (no CDN)`),
  );
}

function renderAll() {
  renderWidgets(() => new HTMLManager({ loader }));
}

// nbconvert's template and myst-nb load the embedder at different moments
if (!window._jupyter_widget_embedder) {
  window._jupyter_widget_embedder = true;
  if (document.readyState === "complete") {
    renderAll();
  } else {
    window.addEventListener("load", renderAll);
  }
}
