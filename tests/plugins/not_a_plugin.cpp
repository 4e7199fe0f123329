// A shared library that is not a hapsyn plugin (no hapsyn_plugin_info symbol).
extern "C" int not_a_plugin_function() { return 42; }
