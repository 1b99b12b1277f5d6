// SPDX-License-Identifier: Apache-2.0
#include "cli/config_file.h"

#include "cli/command_support.h"

#include <algorithm>
#include <filesystem>
#include <istream>
#include <iterator>
#include <map>
#include <memory>
#include <sstream>
#include <vector>

namespace sharcbake {
namespace {

/// Path values read from config files, as resolved (the key) and as the file writes them.
std::map<std::string, std::string>& pathsAsWritten() {
    static std::map<std::string, std::string> paths;
    return paths;
}

/// The options given values by config files, by name ("--view-region"), and where: "FILE ([bake]
/// view-region)".
std::map<std::string, std::string>& optionSources() {
    static std::map<std::string, std::string> sources;
    return sources;
}

/// `value` read from a config file in `folder`: a relative path becomes relative to the folder.
std::string relativeToConfig(const std::filesystem::path& folder, const std::string& value) {
    if (value.empty() || isStandardOutput(value) || folder.empty() || !std::filesystem::path(value).is_relative()) {
        return value;
    }
    const std::string resolved = (folder / value).string();
    pathsAsWritten().emplace(resolved, value);
    return resolved;
}

/// Sections and keys nest at most this deep. sharcbake's options are one level deep ([bake]
/// iterations); CLI11 copies a section's whole path into an item per level, so its work grows
/// with the square of the depth: a 40 KB header of 20,000 dotted parts took 58 s and 12 GB.
constexpr size_t kMaxConfigNesting = 16;

/// The dotted parts of a line's section header ("[a.b]") or key ("a.b = 1"); 0 for other lines
/// (comments, and values continued from the line before, which may hold dotted paths).
/// Quoted parts may hold dots, which are counted too: that can only overcount.
size_t nestingOf(const std::string& line) {
    const size_t first = line.find_first_not_of(" \t");
    if (first == std::string::npos || line[first] == '#') return 0;
    const bool section = line[first] == '[';
    const size_t end = section ? line.find(']', first) : line.find('=', first);
    if (!section && end == std::string::npos) return 0;  // a value continued from the line before
    const std::string name = line.substr(first, end == std::string::npos ? std::string::npos : end - first);
    return size_t(std::count(name.begin(), name.end(), '.')) + 1;
}

/// Values in all of a file's lists together at most. CLI11's reader takes time that grows faster
/// than the count (100,000 values 0.3 s, 300,000 1.4 s, 1,000,000 21 s); sharcbake's options take
/// one value each, and a list only to bake several scenes.
constexpr size_t kMaxConfigListValues = 10000;

/// The commas outside strings and comments in `text`: the separators of its lists' values (TOML's
/// inline tables, which sharcbake's options never take, count too: that can only overcount).
size_t listSeparators(const std::string& text) {
    size_t commas = 0;
    char quote = 0;  // the quote of the string the scan is in, or 0
    bool comment = false;
    for (size_t i = 0; i < text.size(); ++i) {
        const char c = text[i];
        if (comment) {
            comment = c != '\n';
        } else if (quote) {
            if (c == '\\' && quote == '"') ++i;  // an escaped character, "\"" included
            else if (c == quote) quote = 0;
        } else if (c == '"' || c == '\'') {
            quote = c;
        } else if (c == '#') {
            comment = true;
        } else if (c == ',') {
            ++commas;
        }
    }
    return commas;
}

/// "[bake] iterations" for a key of a section, "iterations" for one outside any.
std::string keyName(const CLI::ConfigItem& item) {
    std::string section;
    for (const std::string& parent : item.parents) section += (section.empty() ? "" : ".") + parent;
    return section.empty() ? item.name : "[" + section + "] " + item.name;
}

/// CLI11's TOML reader, which also applies the file's values itself, one by one, so that a value
/// an option refuses is reported with the file's name (CLI11 applies the values it returns only
/// to options still empty: these are no longer). The rules are CLI11's own (App::
/// _parse_single_config): the command line overrides the file; flags take true/false values.
class ConfigFileReader : public CLI::ConfigTOML {
public:
    explicit ConfigFileReader(CLI::App& app) : app_(app) {}

    std::vector<CLI::ConfigItem> from_config(std::istream& input) const override {
        // Read when --config names a file, so the option holds exactly one value.
        const std::string file = app_.get_config_ptr()->as<std::string>();
        // Read here first, to refuse what would make CLI11's reader take quadratic time.
        std::string text{std::istreambuf_iterator<char>(input), std::istreambuf_iterator<char>()};
        std::istringstream lines(text);
        std::string line;
        for (size_t number = 1; std::getline(lines, line); ++number) {
            const size_t first = line.find_first_not_of(" \t");
            if (first != std::string::npos && line[first] == '[' && line.find(']', first) == std::string::npos) {
                // CLI11 read "[bake" as a key and said "[bake is not an option".
                throw CLI::ConfigError(file + ":" + std::to_string(number) +
                                       ": a section header without its "
                                       "closing ']' (" +
                                       line.substr(first) + ")");
            }
            const size_t nesting = nestingOf(line);
            if (nesting > kMaxConfigNesting) {
                throw CLI::ConfigError(file + ":" + std::to_string(number) + ": a section or key nested " +
                                       std::to_string(nesting) + " levels deep (at most " +
                                       std::to_string(kMaxConfigNesting) +
                                       "; sharcbake's options are one level deep: [bake] iterations = 512)");
            }
        }
        if (const size_t separators = listSeparators(text); separators >= kMaxConfigListValues) {
            throw CLI::ConfigError(file + ": lists of " + std::to_string(separators + 1) + " values or more (at most " +
                                   std::to_string(kMaxConfigListValues) +
                                   " in all; sharcbake's options take one value each, and a list only to bake several "
                                   "scenes)");
        }
        std::istringstream checked(text);
        std::vector<CLI::ConfigItem> items;
        try {
            items = CLI::ConfigTOML::from_config(checked);
        } catch (const CLI::ParseError& e) {
            throw CLI::ConfigError(file + ": " + e.what());
        }
        const std::filesystem::path folder = std::filesystem::path(file).parent_path();
        for (CLI::ConfigItem& item : items) {
            if (item.name == "++" || item.name == "--") continue;  // the start and end of a section
            CLI::Option* option = findOption(item);
            if (!option) {
                throw CLI::ConfigError(file + ": " + keyName(item) +
                                       " is not an option (a section is a command, [bake], [render], ...; a key "
                                       "is a long option without --, as --print-config writes them)");
            }
            if (!option->get_configurable()) {
                throw CLI::ConfigError(file + ": " + keyName(item) + " cannot be set in a config file");
            }
            if (!option->empty()) continue;  // given on the command line, which overrides the file
            if (isPathOption(*option)) {
                for (std::string& value : item.inputs) value = relativeToConfig(folder, value);
            }
            optionSources()[option->get_name()] = file + " (" + keyName(item) + ")";
            try {
                if (option->get_expected_min() == 0) {  // a flag
                    option->add_result(option->get_flag_value(item.name, to_flag(item)));
                } else {
                    option->add_result(item.inputs);
                    option->run_callback();
                }
            } catch (const CLI::ParseError& e) {
                throw CLI::ConfigError(file + ": " + keyName(item) + ": " +
                                       rangeErrorMessage(e.what(), option->get_type_name()));
            }
        }
        return items;
    }

private:
    /// The option a key names, looked up as CLI11 does: --name, -n, then a positional's name.
    CLI::Option* findOption(const CLI::ConfigItem& item) const {
        CLI::App* command = &app_;
        for (const std::string& parent : item.parents) {
            try {
                command = command->get_subcommand(parent);
            } catch (const CLI::OptionNotFound&) {
                return nullptr;
            }
        }
        CLI::Option* option = command->get_option_no_throw("--" + item.name);
        if (!option && item.name.size() == 1) option = command->get_option_no_throw("-" + item.name);
        if (!option) option = command->get_option_no_throw(item.name);
        return option;
    }

    CLI::App& app_;
};

}  // namespace

void addConfigFileOption(CLI::App& app, const std::string& help) {
    app.config_formatter(std::make_shared<ConfigFileReader>(app));
    app.set_config("--config", "", help)->type_name("FILE");
    app.allow_config_extras(CLI::config_extras_mode::error);
}

std::string withConfigSource(const std::string& message) {
    const size_t colon = message.find(':');
    if (message.rfind("--", 0) != 0 || colon == std::string::npos) return message;
    const auto it = optionSources().find(message.substr(0, colon));
    return it == optionSources().end() ? message : it->second + ": " + message;
}

std::string pathAsGiven(const std::string& value) {
    const auto it = pathsAsWritten().find(value);
    return it == pathsAsWritten().end() ? value : it->second;
}

void makePathOptionsAbsolute(CLI::App& command) {
    for (CLI::Option* option : command.get_options()) {
        if (!isPathOption(*option) || option->count() == 0) continue;
        std::vector<std::string> values = option->results();
        for (std::string& value : values) {
            if (!value.empty() && !isStandardOutput(value)) value = std::filesystem::absolute(value).string();
        }
        option->clear();
        option->add_result(values);
    }
}

}  // namespace sharcbake
