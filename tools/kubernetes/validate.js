// Checks Kubernetes objects against the Kubernetes API's OpenAPI schema, through the
// kubernetes-models package (its validators are generated from that schema: required fields,
// types, enumerations such as completionMode, formats such as resource quantities).
//
//   python3 tools/kubernetes/fetch_packages.py   (or npm ci there; tools/setup.sh --tests does it)
//   node tools/kubernetes/validate.js OBJECTS.json
//
// OBJECTS.json is a list of {"source": "file.yaml#1", "object": {...}}: the YAML documents as
// JSON (tests/farm/kubernetes_test.py converts them; Node has no YAML reader of its own).
// Prints one line per object and exits 1 if any is invalid or of a kind it does not know.
'use strict';

const fs = require('fs');
const path = require('path');

if (process.argv.length !== 3) {
  console.error('usage: node validate.js OBJECTS.json');
  process.exit(2);
}
const objects = JSON.parse(fs.readFileSync(process.argv[2], 'utf8'));
let failures = 0;
for (const { source, object } of objects) {
  const apiVersion = String(object.apiVersion || '');
  const kind = String(object.kind || '');
  // "batch/v1" + "Job" -> kubernetes-models/batch/v1/Job; the core group "v1" -> kubernetes-models/v1/...
  const modulePath = path.join('kubernetes-models', apiVersion, kind);
  let Model;
  try {
    Model = require(modulePath)[kind];
  } catch (e) {
    console.log(`${source}: unknown apiVersion/kind '${apiVersion}' '${kind}'`);
    failures++;
    continue;
  }
  try {
    new Model(object).validate();
    const name = (object.metadata && object.metadata.name) || '(no name)';
    console.log(`${source}: ${apiVersion} ${kind} ${name}: valid`);
  } catch (e) {
    console.log(`${source}: ${apiVersion} ${kind}: ${e.message}`);
    failures++;
  }
}
process.exit(failures === 0 ? 0 : 1);
