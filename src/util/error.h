// src/util/: the error type and exit codes, vector math.
// The one exception type for user-facing failures. Readers throw it with a message that names the
// file (and line:col for XML, key path for JSON); main() catches it once, prints the message on one
// line and exits with its code: 2 = bad input, 3 = device failure, 4 = output failure.
#pragma once
#include <stdexcept>
#include <string>

namespace clrt {

enum class ExitCode : int { Ok = 0, Usage = 1, BadInput = 2, Device = 3, Output = 4 };

class Error : public std::runtime_error {
public:
    explicit Error(const std::string& msg, ExitCode code = ExitCode::BadInput)
        : std::runtime_error(msg), code_(code) {}
    ExitCode code() const { return code_; }

private:
    ExitCode code_;
};

// Warnings go to stderr with a "warning: " prefix; each distinct message is printed once.
void warnOnce(const std::string& msg);
void warn(const std::string& msg);
// Verbose messages (clrt -v) go to stderr.
void setVerbose(bool v);
bool verbose();
void info(const std::string& msg);

}  // namespace clrt
