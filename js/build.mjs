// Bundle every entry js/src/<name>.js into rbm_nb/widgets/static/<name>.js.
//
//   npm --prefix js ci && npm --prefix js run build
//   node js/build.mjs --outdir /some/where     (what tests/test_js_bundle.py does)
//
// The bundles are ES modules (anywidget's `_esm`) and are committed as package
// data, so installing rbm_nb needs no node. esbuild's output depends only on
// its version (pinned in package-lock.json) and the sources, so a fresh build
// must equal the committed files byte for byte.
import { build } from "esbuild";
import { readdirSync } from "node:fs";
import { readFile } from "node:fs/promises";
import { dirname, join, resolve } from "node:path";
import { fileURLToPath } from "node:url";

const here = dirname(fileURLToPath(import.meta.url));
const srcdir = join(here, "src");
let outdir = resolve(here, "..", "rbm_nb", "widgets", "static");
const flag = process.argv.indexOf("--outdir");
if (flag >= 0) {
  outdir = resolve(process.argv[flag + 1]);
}

const entries = readdirSync(srcdir)
  .filter((name) => name.endsWith(".js"))
  .sort()
  .map((name) => join(srcdir, name));

// three's TransformControls (the gizmo of teaching.js) imports from "three";
// the page's three.js is the one inside meshcat's viewer (globalThis.MeshCat.THREE,
// r132), so the module becomes a factory taking that namespace: one three.js
// on the page, and nothing evaluated before meshcat has loaded
const transformControlsFactory = {
  name: "transform-controls-factory",
  setup(b) {
    b.onLoad({ filter: /TransformControls\.js$/ }, async (args) => {
      const text = await readFile(args.path, "utf8");
      const imports = /^import \{([^}]*)\} from 'three';$/m.exec(text);
      const exports = /^export \{([^}]*)\};$/m.exec(text);
      if (!imports || !exports) {
        throw new Error(`${args.path}: not the TransformControls module this build expects`);
      }
      const body = text.replace(imports[0], "").replace(exports[0], "");
      return {
        contents: `export function makeTransformControls(THREE) {\nconst {${imports[1]}} = THREE;\n${body}\nreturn {${exports[1]}};\n}\n`,
        loader: "js",
      };
    });
  },
};

await build({
  entryPoints: entries,
  plugins: [transformControlsFactory],
  outdir,
  bundle: true,
  format: "esm",
  target: "es2020",
  minify: true,
  legalComments: "inline",
  charset: "utf8",
  logLevel: "warning",
});
console.log(`built ${entries.length} bundles into ${outdir}`);
