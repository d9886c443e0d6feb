// An output that appears at its path only when the run succeeds: written to a
// temporary beside it, renamed on commit. formats.md: on any non-zero exit no
// file is left at an output path, not even an older one.
#pragma once
#include <cstdio>
#include <string>

namespace rbcd {

// Removes a file left at an output path by an earlier run (never a directory).
void discard_output(const std::string& path);
// On SIGINT, SIGTERM or SIGHUP the path is unlinked before the process exits.
// Call before the simulation starts.
void remove_on_interrupt(const std::string& path);
// Both paths exist and name the same file.
bool same_file(const std::string& a, const std::string& b);

class OutputFile {
public:
    OutputFile() = default;
    // Creates the temporary; throws InputError naming the path when it cannot.
    explicit OutputFile(std::string path);
    ~OutputFile();
    OutputFile(const OutputFile&) = delete;
    OutputFile& operator=(const OutputFile&) = delete;
    OutputFile(OutputFile&& o) noexcept;
    OutputFile& operator=(OutputFile&& o) noexcept;

    bool active() const { return f_ != nullptr; }
    const std::string& path() const { return path_; }
    void write(const std::string& s) { write(s.data(), s.size()); }
    void write(const char* p, std::size_t n);
    // Flush, close, rename over the path. Throws std::runtime_error on I/O errors.
    void commit();
    // Removes the temporary and whatever stands at the path.
    void abandon();

private:
    std::string path_, tmp_;
    std::FILE* f_ = nullptr;
    bool failed_ = false;
};

} // namespace rbcd
