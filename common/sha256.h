// SHA-256 (FIPS 180-4): the hash that provenance records for the effective
// configuration and every input file. Written here because no library the
// build already uses offers it (zlib has only CRC-32 and Adler-32).
#pragma once
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

namespace rbcd {

class Sha256 {
public:
    Sha256();
    void update(const void* data, std::size_t len);
    // The digest as 64 lower-case hex digits; the object is spent afterwards.
    std::string hex_digest();

private:
    void block(const std::uint8_t* p);
    std::array<std::uint32_t, 8> h_;
    std::array<std::uint8_t, 64> buf_{};
    std::size_t buf_len_ = 0;
    std::uint64_t total_ = 0;   // bytes hashed so far
};

std::string sha256_hex(const std::string& bytes);

} // namespace rbcd
