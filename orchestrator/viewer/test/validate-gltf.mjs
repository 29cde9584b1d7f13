// Runs the Khronos glTF validator on replay.glb files; exits non-zero if any has an
// error (warnings and infos are printed but allowed).
// usage: node test/validate-gltf.mjs FILE.glb...
import { readFile } from "node:fs/promises";
import validator from "gltf-validator";

const files = process.argv.slice(2);
if (files.length === 0) {
  console.error("usage: node test/validate-gltf.mjs FILE.glb...");
  process.exit(2);
}
let failed = false;
for (const file of files) {
  const bytes = new Uint8Array(await readFile(file));
  const report = await validator.validateBytes(bytes, { maxIssues: 50 });
  const { numErrors, numWarnings, numInfos, messages } = report.issues;
  const info = report.info || {};
  console.log(
    `${file}: ${numErrors} error(s), ${numWarnings} warning(s), ${numInfos} info(s); ` +
      `${info.animationCount} animation(s), ${info.totalVertexCount} vertices, ${info.totalTriangleCount} triangles`
  );
  for (const m of messages) {
    if (m.severity <= 1) console.log(`  [${m.severity === 0 ? "error" : "warning"}] ${m.code} ${m.pointer ?? ""}: ${m.message}`);
  }
  if (numErrors > 0) failed = true;
  if (!info.animationCount) {
    console.log(`  ${file}: no animation`);
    failed = true;
  }
}
process.exit(failed ? 1 : 0);
