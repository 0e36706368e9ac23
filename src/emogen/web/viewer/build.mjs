// Build the face viewer: `npm run build` bundles main.js (three.js from npm, look.json and
// shade.glsl from emogen/render) into src/emogen/web/static/build/, with index.html and viewer.css.
import { copyFile, mkdir } from 'node:fs/promises';
import { dirname, join } from 'node:path';
import { fileURLToPath } from 'node:url';
import * as esbuild from 'esbuild';

const here = dirname(fileURLToPath(import.meta.url));
const out = join(here, '..', 'static', 'build');
await mkdir(out, { recursive: true });
await esbuild.build({
  entryPoints: [join(here, 'main.js')],
  bundle: true,
  format: 'esm',
  minify: true,
  sourcemap: false,
  target: ['es2020'],
  loader: { '.glsl': 'text' },
  legalComments: 'eof',
  outfile: join(out, 'viewer.js'),
  logLevel: 'warning',
});
for (const file of ['index.html', 'viewer.css']) {
  await copyFile(join(here, file), join(out, file));
}
console.log(`viewer built in ${out}`);
