#!/bin/sh
# tools/funclen.sh [FILE...] — length in lines of every function definition (from the line
# holding its name to its closing brace at column 0), longest first: LINES FILE:LINE NAME.
# Default: the library (lib/*.c). Functions are written as the house style writes them:
# the definition starts at column 0 and its body ends with "}" at column 0.
[ $# -gt 0 ] || set -- lib/*.c
awk '
FNR == 1 { name = "" }
/^[A-Za-z_][A-Za-z0-9_ \*]*\(/ && !/;[ \t]*$/ && !/^(typedef|struct|enum|return)\b/ {
    s = $0; sub(/\(.*/, "", s); n = split(s, w, /[ \*]+/); name = w[n]; start = FNR; next
}
/^}/ && name != "" { printf "%d %s:%d %s\n", FNR - start + 1, FILENAME, start, name; name = "" }
' "$@" | sort -rn
