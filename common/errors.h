// Error kinds that map to rbcd-sim's exit status (formats.md): InputError is bad
// input, configuration or command line (exit 2); anything else is exit 1.
#pragma once
#include <stdexcept>
#include <string>

namespace rbcd {

class InputError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// "file:line: what" is the one-line shape every input error takes.
inline InputError input_error_at(const std::string& file, unsigned long long line, const std::string& what) {
    return InputError(file + ":" + std::to_string(line) + ": " + what);
}

} // namespace rbcd
