#!/bin/sh
# The library's public API: every function declared in the public headers
# (include/ampath/*.h), one name a line. The shared library exports exactly
# these (the linker version script is made from this list; tests/test_exports.c
# compares it with the symbols of libampath.so). Declarations start at the
# beginning of a line with their return type, as every public header writes them.
dir=${1:-include/ampath}
cat "$dir"/*.h |
    grep -E '^[A-Za-z_][A-Za-z0-9_ *]*\bamp_[a-z0-9_]+\(' |
    grep -vE '^(static|typedef|return)\b' |
    sed -E 's/^[A-Za-z0-9_ *]*\b(amp_[a-z0-9_]+)\(.*/\1/' |
    sort -u
