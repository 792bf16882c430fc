// Offline runtime of an HTML export: runs anywidgets with no kernel.
//
// The page holds a JSON document (script#rbm-export-data):
//   {esm: [module text, ...],
//    models: [{id, esm: index, state: {...}, buffers: [{path: [...], data: base64}],
//              messages: [{content, buffers: [base64, ...]}]}],
//    layout: [model id, ...]}
// Each model gets a small stand-in for the ipywidgets model (get/set/on/off/
// save_changes/send, widget_manager.get_model); "messages" are what the
// kernel would have sent, delivered when the widget says it is ready. The
// widgets' own code (player.js, scene.js, ...) runs unchanged.

function decode(text) {
  const raw = atob(text);
  const bytes = new Uint8Array(raw.length);
  for (let i = 0; i < raw.length; i++) {
    bytes[i] = raw.charCodeAt(i);
  }
  return new DataView(bytes.buffer);
}

class LocalModel {
  constructor(spec, manager) {
    this.id = spec.id;
    this.state = spec.state;
    for (const b of spec.buffers || []) {
      let target = this.state;
      for (const key of b.path.slice(0, -1)) {
        target = target[key];
      }
      target[b.path[b.path.length - 1]] = decode(b.data);
    }
    this.messages = spec.messages || [];
    this.listeners = new Map();
    this.widget_manager = manager;
  }

  get(key) {
    return this.state[key];
  }

  set(key, value) {
    if (typeof key === "object" && key !== null) {
      for (const [k, v] of Object.entries(key)) {
        this.set(k, v);
      }
      return;
    }
    const old = this.state[key];
    this.state[key] = value;
    if (old !== value) {
      this.trigger(`change:${key}`, value);
      this.trigger("change");
    }
  }

  on(name, callback) {
    if (!this.listeners.has(name)) {
      this.listeners.set(name, new Set());
    }
    this.listeners.get(name).add(callback);
  }

  off(name, callback) {
    if (!name) {
      this.listeners.clear();
    } else if (!callback) {
      this.listeners.delete(name);
    } else if (this.listeners.has(name)) {
      this.listeners.get(name).delete(callback);
    }
  }

  trigger(name, ...args) {
    for (const callback of [...(this.listeners.get(name) || [])]) {
      callback(...(name.startsWith("change:") ? [this, ...args] : args));
    }
  }

  save_changes() {}

  send(content) {
    if (content && content.type === "ready") {
      setTimeout(() => {
        for (const m of this.messages) {
          this.trigger("msg:custom", m.content, m.buffers.map(decode));
        }
      }, 0);
    }
  }
}

async function main() {
  const data = JSON.parse(document.getElementById("rbm-export-data").textContent);
  const modules = await Promise.all(
    data.esm.map((text) => {
      const url = URL.createObjectURL(new Blob([text], { type: "text/javascript" }));
      return import(url).then((m) => m.default || m);
    }),
  );
  const models = new Map();
  const manager = {
    get_model: (id) => {
      const model = models.get(id);
      return model ? Promise.resolve(model) : Promise.reject(new Error(`no model ${id}`));
    },
  };
  for (const spec of data.models) {
    models.set(spec.id, new LocalModel(spec, manager));
  }
  for (const spec of data.models) {
    const widget = modules[spec.esm];
    if (widget.initialize) {
      await widget.initialize({ model: models.get(spec.id) });
    }
  }
  const container = document.getElementById("rbm-dashboard");
  for (const id of data.layout) {
    const spec = data.models.find((m) => m.id === id);
    const el = document.createElement("div");
    el.className = "rbm-cell";
    container.appendChild(el);
    await modules[spec.esm].render({ model: models.get(id), el });
  }
  window.rbmExport = { models, ready: true };
  if (data.autoplay) {
    for (const model of models.values()) {
      if (model.get("_rbm_kind") === "player" || "playing" in model.state) {
        model.set("playing", true);
      }
    }
  }
}

main().catch((err) => {
  const box = document.getElementById("rbm-dashboard");
  box.textContent = `rbm_nb export failed to start: ${err}`;
  console.error(err);
});
