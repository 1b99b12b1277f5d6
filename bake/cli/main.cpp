// SPDX-License-Identifier: Apache-2.0
// sharcbake: command-line entry point. Each subcommand lives in its own *_command.cpp; this
// file only maps outcomes to the documented exit codes.
#include "cli/command_support.h"
#include "cli/commands.h"
#include "cli/config_file.h"

#include <CLI/CLI.hpp>

#include <cstdio>
#include <exception>
#include <string>

namespace {

/// "--seed: cannot read "4294967296" as UINT: expected ...", from CLI11's "Could not convert:
/// --seed = 4294967296" and the option's type.
std::string conversionErrorMessage(CLI::App& app, const std::string& what) {
    const std::string prefix = "Could not convert: ";
    const size_t at = what.find(prefix);
    const size_t equals = at == std::string::npos ? std::string::npos : what.find(" = ", at);
    if (equals == std::string::npos) return what;
    const std::string name = what.substr(at + prefix.size(), equals - at - prefix.size());
    const std::string value = what.substr(equals + 3);
    std::string type;
    for (CLI::App* command : app.get_subcommands()) {  // the command being parsed
        if (const CLI::Option* option = command->get_option_no_throw(name)) type = option->get_type_name();
    }
    const char* accepts = type == "UINT"    ? "a whole number of 0 or more, in digits, that fits the option "
                                              "(most hold up to 4294967295)"
                          : type == "INT"   ? "a whole number, in digits, that fits the option"
                          : type == "FLOAT" ? "a number"
                                            : nullptr;
    return name + ": cannot read \"" + value + "\"" + (type.empty() ? "" : " as " + type) +
           (accepts ? std::string(": expected ") + accepts : std::string());
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
    } catch (const CLI::ParseError& e) {
        // CLI11 prints help/version itself (exit 0) and usage errors (nonzero -> our code 1).
        const int code = app.exit(e);
        return code == 0 ? kExitOk : kExitUsage;
    } catch (const CommandError& e) {
        std::fprintf(stderr, "sharcbake: error: %s\n", e.what());
        return e.code();
    } catch (const std::exception& e) {
        std::fprintf(stderr, "sharcbake: error: %s\n", e.what());
        return kExitRuntime;
    }
    return kExitOk;
}
