// `twinbench completion bash`: a bash completion script written from the CLI11 app itself
// (its verbs, and each verb's options), so it cannot drift from the command line. The build
// writes it (cmake/WriteCompletion.cmake) and installs it to
// share/bash-completion/completions/twinbench. CLI11 has no generator of its own.
#pragma once

#include <string>

#include <CLI/CLI.hpp>

namespace twin {

/// Adds the verb `completion SHELL` (bash only), hidden from --help; `shell` receives SHELL.
CLI::App* AddCompletionVerb(CLI::App* app, std::string* shell);

/// The bash completion script of `app`: verbs (the visible subcommands), their options, and
/// file names for positional arguments and option values.
std::string BashCompletion(const CLI::App& app);

}  // namespace twin
