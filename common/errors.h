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

// A failure of the simulated system itself, e.g. the memory answering a
// transaction with an error response: exit 1 with this one-line message.
class RunError : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

// "0x80000040": addresses in messages, as memory maps write them.
inline std::string hex_address(unsigned long long a) {
    static const char digits[] = "0123456789abcdef";
    std::string s;
    do {
        s.insert(s.begin(), digits[a & 15]);
        a >>= 4;
    } while (a);
    return "0x" + s;
}

// "file:line: what" is the one-line shape every input error takes.
inline InputError input_error_at(const std::string& file, unsigned long long line, const std::string& what) {
    return InputError(file + ":" + std::to_string(line) + ": " + what);
}

} // namespace rbcd
