// SPDX-License-Identifier: Apache-2.0
/// @file config_file.h
/// @brief `sharcbake --config FILE`: CLI11's TOML reader with what a build pipeline expects of a
/// settings file kept under version control next to its scene: a relative path in the file is
/// relative to the file's folder, and an error in the file names the file.
#pragma once

#include <CLI/CLI.hpp>

#include <string>

namespace sharcbake {

/// Adds `--config FILE` (with `help`) to the top-level `app` and makes it read the file this way.
/// Call it before the commands are registered. In the file, one section per command ([bake],
/// [render], ...) holds `option = value` lines, the names being the long options without --;
/// the command line overrides the file. The values of path options (pathOption) that are
/// relative are taken relative to the file's folder; "-" (standard output) and absolute paths
/// stay as they are. A key that is no option, an option that cannot be set in a file, or a value
/// the option refuses is a CLI::ConfigError whose message starts with the file's name.
void addConfigFileOption(CLI::App& app, const std::string& help);

/// `message` (an error about an option's value, "--view-region: ...") prefixed with the config file
/// and key that gave the value, when one did: "bake.toml ([bake] view-region): --view-region: ...".
/// Values the commands check themselves, after the file was read, were reported without the file.
std::string withConfigSource(const std::string& message);

/// A path option's value as the user gave it: for a value read from a config file, the text of the
/// file (a relative path there is relative to the file's folder); any other value unchanged. What a
/// bake records in its cache, so that the same config file gives the same bytes from any checkout
/// (the path resolved against the file's folder differed with the checkout's location).
std::string pathAsGiven(const std::string& value);

/// For --print-config: the relative values of `command`'s path options made absolute (from the
/// current folder, where they were given), so that the printed file, read back from wherever it
/// is kept, names the same files. "-" stays standard output.
void makePathOptionsAbsolute(CLI::App& command);

}  // namespace sharcbake
