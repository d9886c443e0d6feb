// A per-test scratch directory, removed with everything in it at the end.
#pragma once
#include <catch2/catch.hpp>

#include <stdlib.h>
#include <zlib.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace rbcd::test {

// A file's whole content ("" when it cannot be read).
inline std::string slurp(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

struct TempDir {
    std::string dir;
    explicit TempDir(const std::string& prefix = "rbcd_test") {
        std::string tmpl = (std::filesystem::temp_directory_path() / (prefix + "_XXXXXX")).string();
        std::vector<char> b(tmpl.begin(), tmpl.end());
        b.push_back('\0');
        REQUIRE(mkdtemp(b.data()) != nullptr);
        dir = b.data();
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(dir, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;

    std::string path(const std::string& name) const { return dir + "/" + name; }
    std::string write(const std::string& name, const std::string& content) const {
        std::string p = path(name);
        std::ofstream out(p, std::ios::binary);
        out.write(content.data(), static_cast<std::streamsize>(content.size()));
        out.close();
        REQUIRE(out.good());
        return p;
    }
    std::string write_gz(const std::string& name, const std::string& content) const {
        std::string p = path(name);
        gzFile g = gzopen(p.c_str(), "wb6");
        REQUIRE(g != nullptr);
        REQUIRE(gzwrite(g, content.data(), static_cast<unsigned>(content.size())) == static_cast<int>(content.size()));
        REQUIRE(gzclose(g) == Z_OK);
        return p;
    }
};

} // namespace rbcd::test
