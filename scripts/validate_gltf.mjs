// Validate a glTF/GLB file with the Khronos glTF validator (npm `gltf-validator`).
// Usage: node scripts/validate_gltf.mjs FILE.glb
// Prints the validator's JSON report; exits 1 when it reports errors, 2 when it cannot run.
import { readFile } from "node:fs/promises";
import path from "node:path";
import * as validator from "gltf-validator";

const file = process.argv[2];
if (!file) {
  console.error("usage: node scripts/validate_gltf.mjs FILE.glb");
  process.exit(2);
}

try {
  const bytes = new Uint8Array(await readFile(file));
  const report = await validator.validateBytes(bytes, {
    uri: path.basename(file),
    maxIssues: 0,
    externalResourceFunction: (uri) =>
      readFile(path.resolve(path.dirname(file), decodeURIComponent(uri))).then(
        (data) => new Uint8Array(data),
      ),
  });
  console.log(JSON.stringify(report, null, 2));
  process.exit(report.issues.numErrors > 0 ? 1 : 0);
} catch (err) {
  console.error(`cannot validate ${file}: ${err}`);
  process.exit(2);
}
