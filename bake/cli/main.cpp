// SPDX-License-Identifier: Apache-2.0
// sharcbake: command-line entry point. Each subcommand lives in its own *_command.cpp; this
// file only maps outcomes to the documented exit codes.
#include "cli/command_support.h"
#include "cli/commands.h"
#include "cli/config_file.h"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

namespace {

/// The type CLI11 shows for option `name` of the command being parsed ("UINT", "FLOAT:POSITIVE"), or "".
std::string optionTypeName(CLI::App& app, const std::string& name) {
    std::string type;
    for (CLI::App* command : app.get_subcommands()) {  // the command being parsed
        if (const CLI::Option* option = command->get_option_no_throw(name)) type = option->get_type_name();
    }
    return type;
}

/// From CLI11's "Could not convert: --seed = 4294967296".
std::string conversionErrorMessage(CLI::App& app, const std::string& what) {
    const std::string prefix = "Could not convert: ";
    const size_t at = what.find(prefix);
    const size_t equals = at == std::string::npos ? std::string::npos : what.find(" = ", at);
    if (equals == std::string::npos) return what;
    const std::string name = what.substr(at + prefix.size(), equals - at - prefix.size());
    return sharcbake::unreadableValueMessage(name, what.substr(equals + 3), optionTypeName(app, name));
}

/// Levenshtein distance, for suggesting the command a typo meant.
size_t editDistance(const std::string& a, const std::string& b) {
    std::vector<size_t> row(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (size_t i = 1; i <= a.size(); ++i) {
        size_t diagonal = row[0];
        row[0] = i;
        for (size_t j = 1; j <= b.size(); ++j) {
            const size_t above = row[j];
            row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
            diagonal = above;
        }
    }
    return row[b.size()];
}

/// Mistakes CLI11 reports in words that do not name them: a misspelt command ("A subcommand is
/// required" for `sharcbake bak scene.gltf`) and --config after the command ("--output is required",
/// then "The following argument was not expected: --config", though the file holds the output).
/// Empty when the command line has neither.
std::string commandLineMistake(CLI::App& app, int argc, char** argv) {
    std::vector<std::string> commands;
    for (const CLI::App* command : app.get_subcommands({})) commands.push_back(command->get_name());
    int at = 1;
    while (at < argc) {  // the top-level options: --config FILE, --config=FILE, --help, --version
        const std::string arg = argv[at];
        if (arg == "--config") {
            at += 2;
        } else if (!arg.empty() && arg[0] == '-') {
            ++at;
        } else {
            break;
        }
    }
    if (at >= argc) return {};
    const std::string command = argv[at];
    if (std::find(commands.begin(), commands.end(), command) == commands.end()) {
        std::string names, closest;
        size_t best = 3;  // suggest only near misses
        for (const std::string& name : commands) {
            names += (names.empty() ? "" : ", ") + name;
            const size_t distance = editDistance(command, name);
            if (distance < best) {
                best = distance;
                closest = name;
            }
        }
        return "unknown command '" + command + "'" + (closest.empty() ? "" : " (did you mean '" + closest + "'?)") +
               "; the commands are " + names;
    }
    for (int i = at + 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--config" || arg.rfind("--config=", 0) == 0) {
            return "--config goes before the command, as it reads sections for every command: sharcbake --config "
                   "FILE " +
                   command + " ...";
        }
    }
    return {};
}

/// CLI11's "The following arguments were not expected: 4 --iterations" lists them backwards and
/// does not say where an option belongs: "render: not expected: --iterations 4 (--iterations is an
/// option of bake)".
std::string extrasMessage(CLI::App& app) {
    std::vector<std::string> extras;
    std::string where;
    for (CLI::App* command : app.get_subcommands()) {  // the command that was parsed
        const std::vector<std::string> remaining = command->remaining();
        extras.insert(extras.end(), remaining.begin(), remaining.end());
        where = command->get_name();
    }
    for (const std::string& extra : app.remaining()) extras.push_back(extra);
    std::string listed, hints;
    for (const std::string& extra : extras) {
        listed += (listed.empty() ? "" : " ") + extra;
        if (extra.rfind("--", 0) != 0) continue;
        const std::string name = extra.substr(0, extra.find('='));
        for (const CLI::App* command : app.get_subcommands({})) {
            if (command->get_name() != where && command->get_option_no_throw(name)) {
                hints += (hints.empty() ? " (" : "; ") + name + " is an option of " + command->get_name();
                break;
            }
        }
    }
    return (where.empty() ? "" : where + ": ") + "not expected: " + listed + (hints.empty() ? "" : hints + ")");
}

}  // namespace

int main(int argc, char** argv) {
    using namespace sharcbake;
    // Lines in the order they are printed among the warnings, also where both streams go to one
    // log (a pipeline's `2>&1`): piped, stdout was buffered whole until exit while stderr is not
    // buffered, so warnings landed above the summary they follow, or inside one of its lines.
    std::setvbuf(stdout, nullptr, _IOLBF, BUFSIZ);
    CLI::App app{
        "sharcbake " SHARCBAKE_VERSION
        ": offline baker for SHaRC-style world-space radiance caches.\n\n"
        "Loads a static glTF 2.0 scene, traces it on the CPU with Embree and bakes a spatially\n"
        "hashed radiance cache. Run 'sharcbake <command> --help' for each command's options.",
        "sharcbake"};
    app.require_subcommand(1);
    app.footer(kExitCodeHelp);
    app.set_version_flag("--version", "sharcbake " SHARCBAKE_VERSION);
    // Settings under version control: a TOML file with a [bake] (or [render], ...) section of
    // option = value lines; the command line overrides it. An unknown key is an error, so a
    // typo cannot silently fall back to a default. Before the commands, which take its reader.
    addConfigFileOption(app,
                        "Read options from a TOML file, one section per command ([bake], [render], ...; the "
                        "names are the long options without --); the command line overrides it. Relative paths "
                        "in the file (the scene, -o, --checkpoint, --stats-json, --sky-exr, --camera-path, ...) "
                        "are relative to the file's folder, so it can be kept beside its scene. 'sharcbake bake "
                        "... --print-config' writes one. Give it before the command: sharcbake --config FILE bake "
                        "...");
    registerRenderCommand(app);
    registerBakeCommand(app);
    registerInfoCommand(app);
    registerCompareCommand(app);
    registerExportVdbCommand(app);
    registerMergeCommand(app);

    if (const std::string mistake = commandLineMistake(app, argc, argv); !mistake.empty()) {
        std::fprintf(stderr, "sharcbake: error: %s\nRun with --help for more information.\n", mistake.c_str());
        return kExitUsage;
    }
    try {
        app.parse(argc, argv);
    } catch (const CLI::FileError& e) {
        // --config naming a file that cannot be read: an I/O error, as for any other input.
        std::fprintf(stderr, "sharcbake: error: --config: %s\n", e.what());
        return kExitIo;
    } catch (const CLI::ConversionError& e) {
        // CLI11's own words, "Could not convert: --seed = 4294967296", say neither what the option
        // takes nor why the value is not it: name the option's type and what it accepts.
        std::fprintf(stderr, "sharcbake: error: %s\nRun with --help for more information.\n",
                     conversionErrorMessage(app, e.what()).c_str());
        return kExitUsage;
    } catch (const CLI::ValidationError& e) {
        const std::string what = e.what();
        std::fprintf(stderr, "sharcbake: error: %s\nRun with --help for more information.\n",
                     sharcbake::rangeErrorMessage(what, optionTypeName(app, what.substr(0, what.find(':')))).c_str());
        return kExitUsage;
    } catch (const CLI::ConfigError& e) {
        // The reader's messages start with the file's name (config_file.h).
        std::fprintf(stderr, "sharcbake: error: %s\n", e.what());
        return kExitUsage;
    } catch (const CLI::ExtrasError& e) {
        std::fprintf(stderr, "sharcbake: error: %s\nRun with --help for more information.\n",
                     extrasMessage(app).c_str());
        return kExitUsage;
    } catch (const CLI::ParseError& e) {
        // CLI11 prints help/version itself (exit 0) and usage errors (nonzero -> our code 1).
        const int code = app.exit(e);
        return code == 0 ? kExitOk : kExitUsage;
    } catch (const CommandError& e) {
        const std::string message = e.code() == kExitUsage ? withConfigSource(e.what()) : std::string(e.what());
        std::fprintf(stderr, "sharcbake: error: %s\n", message.c_str());
        return e.code();
    } catch (const std::exception& e) {
        std::fprintf(stderr, "sharcbake: error: %s\n", e.what());
        return kExitRuntime;
    }
    return kExitOk;
}
