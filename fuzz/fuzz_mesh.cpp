// The mesh loader (assimp through load_mesh_file_in_process; rbcd-sim runs
// the same in a child process, which contains what assimp itself does wrong). The first byte picks the
// file extension assimp sees; the rest is the file.
#include <unistd.h>

#include <cstdio>
#include <string>

#include "fuzz/fuzz_util.h"
#include "scene/mesh.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size < 1) return 0;
    static const char* const ext[] = {".obj", ".ply", ".stl", ".off", ".gltf", ".glb", ".dae", ".3ds"};
    const std::string path = "/tmp/rbcd-fuzz-mesh-" + std::to_string(::getpid()) + ext[data[0] & 7];
    {
        std::FILE* f = std::fopen(path.c_str(), "wb");
        if (!f) std::abort();
        std::fwrite(data + 1, 1, size - 1, f);
        std::fclose(f);
    }
    rbcd::scene::Mesh m;
    std::string err;
    if (rbcd::scene::load_mesh_file_in_process(path, m, err)) {
        for (const auto& t : m.tris)
            for (auto i : t)
                if (i >= m.verts.size()) rbcd::fuzz::finding("triangle index out of range");
    }
    ::unlink(path.c_str());
    return 0;
}
