#!/usr/bin/env node
// Validates glTF files with the Khronos glTF-Validator (npm package `gltf-validator`, installed by
// scripts/install-deps under $TINCULL_NODE_PREFIX, default ~/.cache/tincull-node). Prints one JSON line per file
// with the numbers of errors, warnings, infos and hints and the error messages; exits 1 when any file has errors,
// 2 when the validator is not installed.
const fs = require('fs');
const path = require('path');
const os = require('os');

const prefix = process.env.TINCULL_NODE_PREFIX || path.join(os.homedir(), '.cache', 'tincull-node');
let validator;
try {
    validator = require(path.join(prefix, 'node_modules', 'gltf-validator'));
} catch (e) {
    console.error(`gltf-validator is not installed under ${prefix}: run scripts/install-deps`);
    process.exit(2);
}

(async () => {
    let failed = false;
    for (const file of process.argv.slice(2)) {
        const dir = path.dirname(file);
        const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), {
            uri: path.basename(file),
            maxIssues: 100,
            externalResourceFunction: (uri) =>
                new Promise((resolve, reject) => {
                    fs.readFile(path.join(dir, decodeURIComponent(uri)), (err, data) =>
                        err ? reject(err.toString()) : resolve(new Uint8Array(data)));
                }),
        });
        const i = report.issues;
        const errors = i.messages.filter((m) => m.severity === 0).map((m) => `${m.code} ${m.pointer || ''}: ${m.message}`);
        console.log(JSON.stringify({
            file, validator: report.validatorVersion, errors: i.numErrors, warnings: i.numWarnings,
            infos: i.numInfos, hints: i.numHints, error_messages: errors,
            messages: i.messages.slice(0, 20).map((m) => `${m.code} (severity ${m.severity}) ${m.pointer || ''}: ${m.message}`),
        }));
        if (i.numErrors > 0) failed = true;
    }
    process.exit(failed ? 1 : 0);
})().catch((e) => {
    console.error(`gltf-validate: ${e}`);
    process.exit(1);
});
