// Bundle every js/src/<name>.js into rbm_nb/widgets/static/<name>.js (ES
// modules, minified, dependencies and CSS inlined) for anywidget's _esm.
import { readdirSync } from "node:fs";
import { dirname, join } from "node:path";
import { fileURLToPath } from "node:url";
import { build } from "esbuild";

const here = dirname(fileURLToPath(import.meta.url));
const src = join(here, "src");
const out = join(here, "..", "rbm_nb", "widgets", "static");
const entries = readdirSync(src).filter((f) => f.endsWith(".js")).map((f) => join(src, f));

await build({
  entryPoints: entries,
  bundle: true,
  format: "esm",
  minify: true,
  target: "es2020",
  outdir: out,
  loader: { ".css": "text" },
  legalComments: "eof",
  logLevel: "info",
});
