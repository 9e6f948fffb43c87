#!/usr/bin/env bash
# The grammar test: vscode-textmate and vscode-oniguruma from npm (tests/grammar/package.json),
# installed once into the build folder, then tokenize.mjs over every example. Exit 77 (ctest:
# skipped) where node or npm is missing or the registry cannot be reached.
#   run.sh SOURCE_DIR BUILD_DIR
set -uo pipefail
src=$1
dir=$2/grammar-test
command -v node >/dev/null || { echo "SKIPPED: no node (apt-get install nodejs npm)"; exit 77; }
mkdir -p "$dir"
cp "$src/tests/grammar/package.json" "$src/tests/grammar/tokenize.mjs" "$dir/"
if [ ! -f "$dir/node_modules/vscode-textmate/package.json" ] || [ ! -f "$dir/node_modules/vscode-oniguruma/package.json" ]; then
  command -v npm >/dev/null || { echo "SKIPPED: no npm (apt-get install npm)"; exit 77; }
  if ! (cd "$dir" && timeout 300 npm install --no-audit --no-fund --no-package-lock --silent >npm.log 2>&1); then
    echo "SKIPPED: npm could not install vscode-textmate (offline?):"
    tail -5 "$dir/npm.log"
    exit 77
  fi
fi
node "$dir/tokenize.mjs" "$src/grammar/sdf.tmLanguage.json" "$src"/examples/*.sdf "$src"/examples/lib/*.sdf "$src"/tests/gpu/scenes/*.sdf
