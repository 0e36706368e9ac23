// Bundle the face viewer's FaceGrid (three.js from npm) as an ES module for the study pages:
// `node src/emogen/web/build_study_viewer.mjs` → src/emogen/web/static/build/study-viewer.js.
import { mkdir } from "node:fs/promises";
import { dirname, join } from "node:path";
import { fileURLToPath } from "node:url";
import * as esbuild from "esbuild";

const here = dirname(fileURLToPath(import.meta.url));
const out = join(here, "static", "build");
await mkdir(out, { recursive: true });
await esbuild.build({
  entryPoints: [join(here, "viewer_entry.js")],
  bundle: true,
  format: "esm",
  minify: true,
  target: ["es2020"],
  loader: { ".glsl": "text" },
  legalComments: "eof",
  outfile: join(out, "study-viewer.js"),
  logLevel: "warning",
});
console.log(`study viewer built in ${out}`);
