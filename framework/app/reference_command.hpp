#pragma once
// `hapsyn reference`: everything the documentation's reference pages are generated from, as one
// JSON document (scripts/gen-reference.py renders it into docs/reference/). Hidden from --help:
// it serves the docs build, not the user.
#include <hapsyn/json.hpp>
#include <hapsyn/internal/registry.hpp>

#include <CLI/CLI.hpp>

namespace hapsyn_cli {

/// Every subcommand of `app` with its positionals and options as CLI11 holds them (names,
/// description, type, default, required, repeatable, flag), hidden ones left out.
hapsyn::Json cli_reference(const CLI::App& app);

/// {"version", "cli", "problem_file", "result_json", "plugins"}: the CLI, the problem file's schema,
/// result.json's declared fields and every plugin the registry finds (its options schema; for a
/// mechanism, its design variables and constraints with the default options when it has them).
hapsyn::Json reference_document(const CLI::App& app, const hapsyn::Registry& registry);

}  // namespace hapsyn_cli
