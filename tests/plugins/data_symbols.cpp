// A shared library whose hapsyn_plugin_info and hapsyn_plugin_create are data, not functions:
// calling them as functions jumps into non-executable memory (it once crashed `hapsyn plugins`).
extern "C" {
char hapsyn_plugin_info[64] = "not a function";
char hapsyn_plugin_create[64] = "not a function either";
}
