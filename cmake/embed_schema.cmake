# Writes a C++ source that embeds a plugin's schema.json as a string literal.
# Called at build time: cmake -DSCHEMA=... -DOUT=... -P embed_schema.cmake
file(READ "${SCHEMA}" content)
set(delim "hapsyn_schema")
file(WRITE "${OUT}.tmp" "// Generated from ${SCHEMA}; do not edit.\nextern const char* const hapsyn_plugin_schema_json;\nconst char* const hapsyn_plugin_schema_json = R\"${delim}(${content})${delim}\";\n")
file(RENAME "${OUT}.tmp" "${OUT}")
