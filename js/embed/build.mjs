// Bundle src/embed.js (Jupyter's HTML widget manager + anywidget) into
// docs/_static/widgets/embed.js and embed.css, for pages without a kernel.
//
//   npm --prefix js/embed ci && node js/embed/build.mjs [--outdir DIR]
//
// Versions are pinned by package-lock.json; esbuild's output depends only on
// them and the sources, so a rebuild equals the committed files byte for byte
// (tests/notebook/test_js_bundle.py checks this).
import { build } from "esbuild";
import { readFile } from "node:fs/promises";
import { dirname, join, resolve } from "node:path";
import { fileURLToPath } from "node:url";

const here = dirname(fileURLToPath(import.meta.url));
let outdir = resolve(here, "..", "..", "docs", "_static", "widgets");
const flag = process.argv.indexOf("--outdir");
if (flag >= 0) {
  outdir = resolve(process.argv[flag + 1]);
}

// anywidget's dist/index.js ends in an AMD define() for a CDN loader; export
// the factory instead so the bundle can call it with @jupyter-widgets/base
const anywidgetAsModule = {
  name: "anywidget-as-module",
  setup(b) {
    b.onLoad({ filter: /anywidget[\\/]dist[\\/]index\.js$/ }, async (args) => {
      const text = await readFile(args.path, "utf8");
      const amd = 'define(["@jupyter-widgets/base"], widget_default);';
      if (!text.includes(amd)) {
        throw new Error("anywidget's bundle no longer ends in the expected define()");
      }
      return { contents: text.replace(amd, "export { widget_default as widgetModule };"), loader: "js" };
    });
  },
};

await build({
  entryPoints: { embed: join(here, "src", "embed.js") },
  outdir,
  bundle: true,
  format: "iife",
  target: "es2020",
  minify: true,
  legalComments: "eof",
  charset: "utf8",
  logLevel: "warning",
  // browsers that run this bundle read woff2; the older font formats are left out
  loader: { ".woff2": "file", ".woff": "empty", ".ttf": "empty", ".eot": "empty", ".svg": "empty" },
  assetNames: "[name]-[hash]",
  define: { "process.env.NODE_ENV": '"production"' },
  // @jupyter-widgets/html-manager sets webpack's public path for its fonts
  banner: { js: "var __webpack_public_path__ = \"\";" },
  plugins: [anywidgetAsModule],
});
console.log(`built embed.js and embed.css into ${outdir}`);
