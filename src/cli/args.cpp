// args.cpp — the table-driven argument walk and the value parsers of args.h (every usage error of
// the commands' options comes from here). Reads no scene element.
#include "cli/args.h"

#include <cerrno>
#include <cmath>
#include <cstdlib>

#include "util/error.h"

namespace clrt {

ArgOption flagOption(std::vector<std::string> names, bool& target) {
    return {std::move(names), false, [&target](const std::string&, const std::string&) { target = true; }};
}

ArgOption textOption(std::vector<std::string> names, std::string& target) {
    return {std::move(names), true, [&target](const std::string&, const std::string& v) { target = v; }};
}

std::vector<std::string> parseArgs(int argc, char** argv, int start, const std::vector<ArgOption>& options,
                                   const std::string& command) {
    std::vector<std::string> positional;
    for (int i = start; i < argc; ++i) {
        const std::string s = argv[i];
        const ArgOption* opt = nullptr;
        for (const ArgOption& o : options)
            for (const std::string& n : o.names)
                if (n == s) opt = &o;
        if (!opt) {
            if (!s.empty() && s[0] == '-')
                throw Error("unknown option '" + s + "' (see clrt " + command + " --help)", ExitCode::Usage);
            positional.push_back(s);
            continue;
        }
        if (opt->hasValue && i + 1 >= argc) throw Error(s + ": missing value", ExitCode::Usage);
        opt->take(s, opt->hasValue ? std::string(argv[++i]) : std::string());
        if (opt->endsParsing) break;
    }
    return positional;
}

void throwExpected(const std::string& flag, const std::string& what, const std::string& value) {
    throw Error(flag + ": expected " + what + ", got '" + value + "'", ExitCode::Usage);
}

int parseIntArg(const std::string& flag, const std::string& v, long lo, long hi) {
    char* end = nullptr;
    errno = 0;
    const long x = std::strtol(v.c_str(), &end, 10);
    if (v.empty() || *end != '\0' || errno != 0 || x < lo || x > hi)
        throwExpected(flag, "an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]", v);
    return int(x);
}

double parseBoundedArg(const std::string& flag, const std::string& v, double lo, bool open) {
    char* end = nullptr;
    errno = 0;
    const double x = std::strtod(v.c_str(), &end);
    if (v.empty() || *end != '\0' || errno != 0 || !std::isfinite(x) || x < lo || (open && x == lo))
        throwExpected(flag, std::string("a number ") + (open ? "> " : ">= ") + std::to_string(int(lo)), v);
    return x;
}

float parseFloatArg(const std::string& flag, const std::string& v) {
    char* end = nullptr;
    errno = 0;
    const float x = std::strtof(v.c_str(), &end);
    if (v.empty() || *end != '\0' || errno != 0 || !std::isfinite(x)) throwExpected(flag, "a number", v);
    return x;
}

std::string choiceList(std::initializer_list<const char*> choices) {
    std::string out;
    size_t i = 0;
    for (const char* c : choices) {
        if (i > 0) out += i + 1 == choices.size() ? " or " : ", ";
        out += c;
        ++i;
    }
    return out;
}

size_t parseChoiceArg(const std::string& flag, const std::string& v, std::initializer_list<const char*> choices) {
    size_t i = 0;
    for (const char* c : choices) {
        if (v == c) return i;
        ++i;
    }
    throwExpected(flag, choiceList(choices), v);
}

std::pair<std::string, std::string> splitArg(const std::string& flag, const std::string& v, char sep,
                                             const char* form) {
    const size_t at = v.find(sep);
    if (at == std::string::npos) throwExpected(flag, form, v);
    return {v.substr(0, at), v.substr(at + 1)};
}

}  // namespace clrt
