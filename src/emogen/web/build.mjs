// Build the browser bundles (`npm run build`, or `node src/emogen/web/build.mjs`) into
// src/emogen/web/static/build/: the face viewer page (viewer/main.js → viewer.js, with its
// index.html and viewer.css) and the study pages' FaceGrid (viewer_entry.js → study-viewer.js).
// Both bundle three.js from npm and look.json / shade.glsl from emogen/render.
import { copyFile, mkdir } from "node:fs/promises";
import { dirname, join } from "node:path";
import { fileURLToPath } from "node:url";
import * as esbuild from "esbuild";

const here = dirname(fileURLToPath(import.meta.url));
const out = join(here, "static", "build");
const bundles = [
  { entry: join(here, "viewer", "main.js"), file: "viewer.js" },
  { entry: join(here, "viewer_entry.js"), file: "study-viewer.js" },
];

await mkdir(out, { recursive: true });
await Promise.all(
  bundles.map(({ entry, file }) =>
    esbuild.build({
      entryPoints: [entry],
      bundle: true,
      format: "esm",
      minify: true,
      sourcemap: false,
      target: ["es2020"],
      loader: { ".glsl": "text" },
      legalComments: "eof",
      outfile: join(out, file),
      logLevel: "warning",
    }),
  ),
);
for (const file of ["index.html", "viewer.css"]) {
  await copyFile(join(here, "viewer", file), join(out, file));
}
console.log(`viewer bundles built in ${out}: ${bundles.map((b) => b.file).join(", ")}`);
