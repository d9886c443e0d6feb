#include "sc_main/output_file.h"

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <unistd.h>
#include <utility>

#include "common/errors.h"

namespace rbcd {

OutputFile::OutputFile(std::string path) : path_(std::move(path)) {
    tmp_ = path_ + ".tmp." + std::to_string(::getpid());
    f_ = std::fopen(tmp_.c_str(), "wb");
    if (!f_) throw InputError(path_ + ": cannot create: " + std::strerror(errno));
    std::setvbuf(f_, nullptr, _IOFBF, 1 << 20);
}

OutputFile::~OutputFile() { abandon(); }

OutputFile::OutputFile(OutputFile&& o) noexcept { *this = std::move(o); }

OutputFile& OutputFile::operator=(OutputFile&& o) noexcept {
    if (this != &o) {
        abandon();
        path_ = std::move(o.path_);
        tmp_ = std::move(o.tmp_);
        f_ = std::exchange(o.f_, nullptr);
        failed_ = o.failed_;
    }
    return *this;
}

void OutputFile::write(const char* p, std::size_t n) {
    if (f_ && n && std::fwrite(p, 1, n, f_) != n) failed_ = true;
}

void OutputFile::commit() {
    if (!f_) return;
    const bool flushed = std::fflush(f_) == 0 && !std::ferror(f_);
    const bool closed = std::fclose(f_) == 0;
    f_ = nullptr;
    if (failed_ || !flushed || !closed) {
        const std::string why = std::strerror(errno);
        std::remove(tmp_.c_str());
        std::remove(path_.c_str());
        throw std::runtime_error(path_ + ": write failed: " + why);
    }
    if (std::rename(tmp_.c_str(), path_.c_str()) != 0) {
        const std::string why = std::strerror(errno);
        std::remove(tmp_.c_str());
        std::remove(path_.c_str());
        throw std::runtime_error(path_ + ": cannot rename into place: " + why);
    }
    tmp_.clear();
}

void OutputFile::abandon() {
    if (f_) {
        std::fclose(f_);
        f_ = nullptr;
    }
    if (!tmp_.empty()) {
        std::remove(tmp_.c_str());
        std::remove(path_.c_str());
        tmp_.clear();
    }
}

} // namespace rbcd
