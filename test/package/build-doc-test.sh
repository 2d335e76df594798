#!/usr/bin/env bash
# Builds the API documentation with the build's Doxyfile and fails on any Doxygen warning (ctest: package.doc).
# Exit 77 (skipped) when doxygen is not installed.
set -euo pipefail
build=$1
command -v doxygen >/dev/null || { echo "doxygen not installed: skipped (apt-get install doxygen)"; exit 77; }
rm -rf "$build/doc"
mkdir -p "$build/doc"
(cd "$build" && doxygen Doxyfile)
if [ -s "$build/doc/warnings.log" ]; then
  echo "Doxygen warnings:"
  cat "$build/doc/warnings.log"
  exit 1
fi
test -f "$build/doc/html/index.html"
echo "documentation built without warnings: $build/doc/html/index.html"
