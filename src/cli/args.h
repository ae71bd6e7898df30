// src/cli/: the clrt commands (render, tonemap, merge) and what they share (argument parsing, output checks, signals).
// args.h — the one command-line parser of the clrt commands (render, tonemap, merge): each command
// lists its options in a table (spellings, whether a value follows, what to do with it), and
// parseArgs walks argv by that table. The value parsers below give every command the same error
// lines ("--spp: expected an integer in [1, 1048576], got 'x'"), all clrt::Error with
// ExitCode::Usage (exit 1). Reads no scene element.
#pragma once
#include <functional>
#include <initializer_list>
#include <string>
#include <utility>
#include <vector>

namespace clrt {

// One option of a command. `take` gets the spelling used (for messages) and the value: the next
// argument when `hasValue`, else "".
struct ArgOption {
    std::vector<std::string> names;  // e.g. {"-o", "--output"}
    bool hasValue = true;
    std::function<void(const std::string& flag, const std::string& value)> take;
    bool endsParsing = false;        // the arguments after it are not looked at (`clrt merge --help`)
};

// An option without a value that sets `target` to true.
ArgOption flagOption(std::vector<std::string> names, bool& target);
// An option whose value is stored as given.
ArgOption textOption(std::vector<std::string> names, std::string& target);

// Walks argv[start..argc) by `options`; returns the arguments that are not options (in order).
// Errors: "FLAG: missing value" (a value option last), "unknown option 'X' (see clrt COMMAND --help)"
// (an argument starting with '-' that no option names).
std::vector<std::string> parseArgs(int argc, char** argv, int start, const std::vector<ArgOption>& options,
                                   const std::string& command);

// Throws "FLAG: expected WHAT, got 'VALUE'" (ExitCode::Usage).
[[noreturn]] void throwExpected(const std::string& flag, const std::string& what, const std::string& value);

// A decimal integer in [lo, hi]; else "FLAG: expected an integer in [lo, hi], got 'v'".
int parseIntArg(const std::string& flag, const std::string& v, long lo, long hi);
// A finite number >= lo (> lo when `open`); else "FLAG: expected a number > lo (>= lo), got 'v'".
double parseBoundedArg(const std::string& flag, const std::string& v, double lo, bool open);
// Any finite float; else "FLAG: expected a number, got 'v'".
float parseFloatArg(const std::string& flag, const std::string& v);
// The index of `v` among `choices`; else "FLAG: expected a, b or c, got 'v'".
size_t parseChoiceArg(const std::string& flag, const std::string& v, std::initializer_list<const char*> choices);
// "a, b or c" of the choices.
std::string choiceList(std::initializer_list<const char*> choices);
// The two halves of "AxB" around `sep`; else "FLAG: expected FORM, got 'v'" (FORM: "WxH", "K/N").
std::pair<std::string, std::string> splitArg(const std::string& flag, const std::string& v, char sep, const char* form);

}  // namespace clrt
