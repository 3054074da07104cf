// Validates glTF / GLB files with the Khronos glTF validator (npm package `gltf-validator`,
// installed by scripts/setup.sh under .tools/gltf-validator).
// Usage: node scripts/validate_gltf.cjs FILE...
// Prints one JSON line per file: {file, errors, warnings, infos, hints, messages}.
// Exit status: 0 when no file has errors or warnings, 1 otherwise, 2 when the validator is
// not installed or cannot read a file.
"use strict";
const fs = require("fs");
const path = require("path");

const where = path.join(__dirname, "..", ".tools", "gltf-validator", "node_modules", "gltf-validator");
let validator;
try {
    validator = require(where);
} catch (e) {
    console.error(`gltf-validator is not installed at ${where} (run scripts/setup.sh)`);
    process.exit(2);
}

async function main(files) {
    let status = 0;
    for (const file of files) {
        const report = await validator.validateBytes(new Uint8Array(fs.readFileSync(file)), { uri: path.basename(file) });
        const issues = report.issues;
        console.log(JSON.stringify({
            file,
            validatorVersion: report.validatorVersion,
            errors: issues.numErrors,
            warnings: issues.numWarnings,
            infos: issues.numInfos,
            hints: issues.numHints,
            messages: issues.messages,
        }));
        if (issues.numErrors > 0 || issues.numWarnings > 0) {
            status = 1;
        }
    }
    return status;
}

main(process.argv.slice(2)).then((status) => process.exit(status), (e) => {
    console.error(String(e));
    process.exit(2);
});
