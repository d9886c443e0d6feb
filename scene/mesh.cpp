#include "rbcd/scene/mesh.h"

#include <atomic>
#include <cctype>
#include <cstdlib>
#include <vector>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <cerrno>
#include <cstring>
#include <csignal>
#include <unistd.h>
#include <sys/wait.h>
#include <fcntl.h>
#include <cstdio>
#include <stdexcept>

#include <dlfcn.h>

#include <Eigen/Geometry>
#include <assimp/cimport.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "rbcd/common/write_all.h"

namespace rbcd::scene {
namespace {

constexpr double kPi = 3.14159265358979323846;

// Adds triangle (a, b, c) wound so that its normal points away from `inside`:
// deriving the winding from geometry rather than from index order keeps every
// shape outward counter-clockwise by construction.
void add_tri(Mesh& m, std::uint32_t a, std::uint32_t b, std::uint32_t c, const Eigen::Vector3d& inside) {
    const Eigen::Vector3d& pa = m.verts[a];
    const Eigen::Vector3d& pb = m.verts[b];
    const Eigen::Vector3d& pc = m.verts[c];
    Eigen::Vector3d n = (pb - pa).cross(pc - pa);
    Eigen::Vector3d centroid = (pa + pb + pc) / 3.0;
    if (n.dot(centroid - inside) >= 0.0) m.tris.push_back({a, b, c});
    else m.tris.push_back({a, c, b});
}

void add_quad(Mesh& m, std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d, const Eigen::Vector3d& inside) {
    add_tri(m, a, b, c, inside);
    add_tri(m, a, c, d, inside);
}

std::uint32_t add_vert(Mesh& m, double x, double y, double z) {
    m.verts.emplace_back(x, y, z);
    return static_cast<std::uint32_t>(m.verts.size() - 1);
}

Mesh make_sphere(unsigned slices) {
    const unsigned stacks = std::max(2u, slices / 2);
    Mesh m;
    const Eigen::Vector3d o = Eigen::Vector3d::Zero();
    const std::uint32_t north = add_vert(m, 0.0, 1.0, 0.0);
    std::vector<std::uint32_t> ring_start;
    for (unsigned i = 1; i < stacks; ++i) {
        const double th = kPi * i / stacks;
        ring_start.push_back(static_cast<std::uint32_t>(m.verts.size()));
        for (unsigned j = 0; j < slices; ++j) {
            const double ph = 2.0 * kPi * j / slices;
            add_vert(m, std::sin(th) * std::cos(ph), std::cos(th), std::sin(th) * std::sin(ph));
        }
    }
    const std::uint32_t south = add_vert(m, 0.0, -1.0, 0.0);
    auto at = [&](unsigned ring, unsigned j) { return ring_start[ring] + (j % slices); };
    for (unsigned j = 0; j < slices; ++j) {
        add_tri(m, north, at(0, j), at(0, j + 1), o);
        for (unsigned r = 0; r + 1 < ring_start.size(); ++r) add_quad(m, at(r, j), at(r + 1, j), at(r + 1, j + 1), at(r, j + 1), o);
        add_tri(m, south, at(static_cast<unsigned>(ring_start.size()) - 1, j + 1), at(static_cast<unsigned>(ring_start.size()) - 1, j), o);
    }
    return m;
}

Mesh make_box() {
    Mesh m;
    for (int i = 0; i < 8; ++i) add_vert(m, (i & 1) ? 1.0 : -1.0, (i & 2) ? 1.0 : -1.0, (i & 4) ? 1.0 : -1.0);
    const Eigen::Vector3d o = Eigen::Vector3d::Zero();
    add_quad(m, 0, 1, 3, 2, o);   // z = -1
    add_quad(m, 4, 5, 7, 6, o);   // z = +1
    add_quad(m, 0, 1, 5, 4, o);   // y = -1
    add_quad(m, 2, 3, 7, 6, o);   // y = +1
    add_quad(m, 0, 2, 6, 4, o);   // x = -1
    add_quad(m, 1, 3, 7, 5, o);   // x = +1
    return m;
}

Mesh make_torus(unsigned major_seg) {
    const unsigned minor_seg = std::max(3u, major_seg / 2);
    const double R = 1.0, r = 0.25;
    Mesh m;
    for (unsigned i = 0; i < major_seg; ++i) {
        const double th = 2.0 * kPi * i / major_seg;
        for (unsigned j = 0; j < minor_seg; ++j) {
            const double ph = 2.0 * kPi * j / minor_seg;
            const double rad = R + r * std::cos(ph);
            add_vert(m, rad * std::cos(th), r * std::sin(ph), rad * std::sin(th));
        }
    }
    auto at = [&](unsigned i, unsigned j) { return (i % major_seg) * minor_seg + (j % minor_seg); };
    for (unsigned i = 0; i < major_seg; ++i) {
        // The tube's axis at this quad: "inside" for winding purposes. The
        // chord's midpoint, not the circle's: with few segments the circle
        // lies outside the inner faces (3 or 4 segments wound them inward).
        const double th = 2.0 * kPi * (i + 0.5) / major_seg;
        const double rc = R * std::cos(kPi / major_seg);
        const Eigen::Vector3d axis(rc * std::cos(th), 0.0, rc * std::sin(th));
        for (unsigned j = 0; j < minor_seg; ++j) add_quad(m, at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1), axis);
    }
    return m;
}

Mesh make_cylinder(unsigned slices) {
    Mesh m;
    const Eigen::Vector3d o = Eigen::Vector3d::Zero();
    const std::uint32_t bottom_c = add_vert(m, 0.0, -1.0, 0.0);
    const std::uint32_t top_c = add_vert(m, 0.0, 1.0, 0.0);
    const std::uint32_t base = static_cast<std::uint32_t>(m.verts.size());
    for (unsigned j = 0; j < slices; ++j) {
        const double ph = 2.0 * kPi * j / slices;
        add_vert(m, std::cos(ph), -1.0, std::sin(ph));
        add_vert(m, std::cos(ph), 1.0, std::sin(ph));
    }
    auto bot = [&](unsigned j) { return base + 2 * (j % slices); };
    auto top = [&](unsigned j) { return base + 2 * (j % slices) + 1; };
    for (unsigned j = 0; j < slices; ++j) {
        add_quad(m, bot(j), bot(j + 1), top(j + 1), top(j), o);
        add_tri(m, bottom_c, bot(j), bot(j + 1), o);
        add_tri(m, top_c, top(j), top(j + 1), o);
    }
    return m;
}

void append_node(const aiScene* s, const aiNode* node, const aiMatrix4x4& parent, Mesh& out) {
    const aiMatrix4x4 xf = parent * node->mTransformation;
    // A mirroring node transform turns the outward winding inward; undo it so
    // the mesh stays outward counter-clockwise (glTF's rule as well).
    const bool mirror = xf.Determinant() < 0.0f;
    for (unsigned mi = 0; mi < node->mNumMeshes; ++mi) {
        const aiMesh* mesh = s->mMeshes[node->mMeshes[mi]];
        const std::uint32_t base = static_cast<std::uint32_t>(out.verts.size());
        for (unsigned v = 0; v < mesh->mNumVertices; ++v) {
            const aiVector3D p = xf * mesh->mVertices[v];
            out.verts.emplace_back(p.x, p.y, p.z);
        }
        for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
            const aiFace& face = mesh->mFaces[f];
            if (face.mNumIndices != 3) continue;   // points and lines cover nothing
            // assimp passes through indices a file gets wrong (found by fuzzing).
            if (face.mIndices[0] >= mesh->mNumVertices || face.mIndices[1] >= mesh->mNumVertices ||
                face.mIndices[2] >= mesh->mNumVertices) {
                out.bad_index = true;
                continue;
            }
            std::uint32_t a = base + face.mIndices[0], b = base + face.mIndices[1], c = base + face.mIndices[2];
            if (mirror) std::swap(b, c);
            out.tris.push_back({a, b, c});
        }
    }
    for (unsigned ci = 0; ci < node->mNumChildren; ++ci) append_node(s, node->mChildren[ci], xf, out);
}

// Some assimp messages mislead: a .gltf whose .bin is missing reports "No
// suitable reader found", an empty ASCII STL "Mesh with invalid primitive type".
// Says what is wrong instead; other messages pass unchanged.
std::string explain_import_error(const std::string& path, const std::string& err) {
    namespace fs = std::filesystem;
    std::string ext = fs::path(path).extension().string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    const bool no_reader = err.find("No suitable reader") != std::string::npos;
    if (ext == ".gltf") {
        // The buffers and images a glTF file names by relative URI.
        std::ifstream in(path, std::ios::binary);
        std::ostringstream text;
        text << in.rdbuf();
        static const std::regex uri(R"re("uri"\s*:\s*"([^"]*)")re");
        const std::string s = text.str();
        for (std::sregex_iterator it(s.begin(), s.end(), uri), end; it != end; ++it) {
            const std::string u = (*it)[1].str();
            if (u.rfind("data:", 0) == 0) continue;
            std::error_code ec;
            if (!fs::exists(fs::path(path).parent_path() / u, ec))
                return "the file '" + u + "' it refers to is missing (looked for beside it)";
        }
        if (no_reader) return "assimp cannot read it as glTF (\"" + err + "\")";
    }
    if (no_reader) return "assimp has no reader for this file format (\"" + err + "\")";
    if (err.find("invalid primitive type") != std::string::npos || err.find("There are no facets") != std::string::npos ||
        err.find("OBJ-file is too small") != std::string::npos)
        return "it holds no triangles";
    if (err == "File is empty") return "the file is empty";
    return err;
}

} // namespace

Mesh builtin_mesh(const std::string& shape, unsigned segments) {
    if (shape == "sphere") return make_sphere(segments);
    if (shape == "box") return make_box();
    if (shape == "torus") return make_torus(segments);
    if (shape == "cylinder") return make_cylinder(segments);
    throw std::logic_error("builtin_mesh: unknown shape " + shape);
}

std::uint64_t builtin_triangles(const std::string& shape, unsigned segments) {
    const std::uint64_t s = segments;
    if (shape == "sphere") return 2 * s * (std::max<std::uint64_t>(2, s / 2) - 1);
    if (shape == "box") return 12;
    if (shape == "torus") return 2 * s * std::max<std::uint64_t>(3, s / 2);
    if (shape == "cylinder") return 4 * s;
    throw std::logic_error("builtin_triangles: unknown shape " + shape);
}

namespace {
std::vector<std::string> words_of(const std::string& line) {
    std::vector<std::string> w;
    std::size_t i = 0;
    while (true) {
        i = line.find_first_not_of(" \t\r", i);
        if (i == std::string::npos) break;
        const std::size_t e = line.find_first_of(" \t\r", i);
        w.push_back(line.substr(i, e == std::string::npos ? std::string::npos : e - i));
        if (e == std::string::npos) break;
        i = e;
    }
    return w;
}

bool is_count(const std::string& w, std::uint64_t& v) {
    if (w.empty() || w.size() > 18 || w.find_first_not_of("0123456789") != std::string::npos) return false;
    v = std::stoull(w);
    return true;
}

bool is_number(const std::string& w) {
    char* end = nullptr;
    std::strtod(w.c_str(), &end);
    return !w.empty() && end == w.c_str() + w.size();
}

// assimp 5.2 (Debian) mishandles malformed PLY files, all found by fuzzing:
// it never returns from a header without end_header, calls abort() on some
// broken headers, and on a body that does not match its header reads freed
// memory, so that the mesh it returns depends on the heap. A PLY file is
// therefore checked before assimp sees it: its header line by line, and an
// ASCII body entry by entry against the header (every entry one line, one
// number per scalar property, a list's count then that many numbers, face
// indices below the vertex count), as far as assimp's own reading allows
// (free-text header lines; a list missing at the end of a line). Binary
// bodies are left to assimp.
bool ply_file_ok(const std::string& path, std::string& error) {
    std::ifstream in(path, std::ios::binary);
    if (!in) return true;   // assimp reports it
    std::string line;
    std::string ext = path.size() >= 4 ? path.substr(path.size() - 4) : std::string();
    for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    // assimp takes a file for PLY by its extension or by "ply" at the start.
    const int first = in.peek();
    if (ext != ".ply" && first != 'p') return true;
    if (!std::getline(in, line)) return true;
    if (words_of(line) != std::vector<std::string>{"ply"}) {
        if (ext != ".ply") return true;   // not a PLY file: another reader's
        error = "PLY line 1: not \"ply\"";
        return false;
    }

    struct Property {
        bool list = false;
        std::string name;
    };
    struct Element {
        std::string name;
        std::uint64_t count = 0;
        std::vector<Property> props;
    };
    std::vector<Element> elements;
    bool ascii = false, format = false, ended = false;
    std::uint64_t n = 1, header_bytes = line.size() + 1;
    const auto bad = [&](const std::string& what) {
        error = "PLY line " + std::to_string(n) + ": " + what;
        return false;
    };
    while (std::getline(in, line)) {
        ++n;
        header_bytes += line.size() + 1;
        if (header_bytes > 65536) return bad("no end_header line in the first 64 KiB");
        const auto w = words_of(line);
        if (w.empty()) continue;
        if (w[0] == "comment" || w[0] == "obj_info") continue;
        if (w[0] == "end_header" && w.size() == 1) {
            ended = true;
            break;
        }
        if (w[0] == "format" && w.size() == 3 && !format) {
            if (w[1] != "ascii" && w[1] != "binary_little_endian" && w[1] != "binary_big_endian")
                return bad("unknown format '" + w[1] + "'");
            format = true;
            ascii = w[1] == "ascii";
            continue;
        }
        std::uint64_t count = 0;
        if (w[0] == "element" && w.size() == 3 && is_count(w[2], count)) {
            elements.push_back({w[1], count, {}});
            continue;
        }
        if (w[0] == "property" && !elements.empty() && (w.size() == 3 || (w.size() == 5 && w[1] == "list"))) {
            elements.back().props.push_back({w.size() == 5, w.back()});
            continue;
        }
        // Other lines are free text, as assimp takes them (Blender writes
        // comments without the keyword); a keyword line must be well formed.
        if (w[0] == "format" || w[0] == "element" || w[0] == "property" || w[0] == "end_header")
            return bad("malformed '" + w[0] + "' line");
    }
    if (!ended) return bad("no end_header line");
    if (!format) return bad("no format line in the header");
    if (!ascii) return true;

    std::uint64_t vertices = 0;
    for (const auto& e : elements)
        if (e.name == "vertex") vertices = e.count;
    for (const auto& e : elements) {
        for (std::uint64_t k = 0; k < e.count; ++k) {
            if (!std::getline(in, line)) {
                ++n;
                return bad("the file ends inside element '" + e.name + "' (" + std::to_string(k) + " of " +
                           std::to_string(e.count) + " entries)");
            }
            ++n;
            const auto w = words_of(line);
            std::size_t at = 0;
            for (const auto& p : e.props) {
                // A list missing at the end of the line is an empty one, as
                // assimp reads it (its own test model issue623.ply).
                if (at >= w.size() && p.list) continue;
                if (at >= w.size()) return bad("element '" + e.name + "': too few values for its properties");
                if (!p.list) {
                    if (!is_number(w[at++])) return bad("element '" + e.name + "': not a number: '" + w[at - 1] + "'");
                    continue;
                }
                std::uint64_t len = 0;
                if (!is_count(w[at++], len)) return bad("element '" + e.name + "': not a list length: '" + w[at - 1] + "'");
                if (w.size() - at < len) return bad("element '" + e.name + "': a list of " + std::to_string(len) +
                                                    " holds fewer values");
                const bool indices = e.name == "face" && (p.name == "vertex_index" || p.name == "vertex_indices");
                for (std::uint64_t i = 0; i < len; ++i, ++at) {
                    std::uint64_t v = 0;
                    if (indices ? !is_count(w[at], v) || v >= vertices : !is_number(w[at]))
                        return bad(indices ? "a face refers to vertex '" + w[at] + "' of " + std::to_string(vertices)
                                           : "element '" + e.name + "': not a number: '" + w[at] + "'");
                }
            }
            if (at != w.size()) return bad("element '" + e.name + "': more values than its properties");
        }
    }
    return true;
}
} // namespace

namespace {
// assimp's C interface, opened the first time a mesh file is read: nothing
// links assimp, so a run that reads no mesh file (every trace, the default
// scene, a --jobs worker) starts without loading and relocating it, a
// library of 44,000 relocations: linked, 1.4 ms of rbcd-sim's 5 ms start.
// A library that cannot be opened is that mesh file's error.
struct AssimpC {
    decltype(&aiImportFile) import_file = nullptr;
    decltype(&aiReleaseImport) release_import = nullptr;
    decltype(&aiGetErrorString) error_string = nullptr;
    std::string missing;   // why it could not be opened
};
const AssimpC& assimp_c() {
    static const AssimpC a = [] {
        AssimpC r;
        void* h = ::dlopen(RBCD_ASSIMP_SONAME, RTLD_NOW | RTLD_LOCAL);
        // An assimp outside the loader's paths: the file the build found.
        if (!h) h = ::dlopen(RBCD_ASSIMP_FILE, RTLD_NOW | RTLD_LOCAL);
        if (!h) {
            const char* why = ::dlerror();
            r.missing = std::string("cannot load assimp (" RBCD_ASSIMP_SONAME "), which reads mesh files: ") +
                        (why ? why : "dlopen failed") + " (Debian: libassimp5)";
            return r;
        }
        r.import_file = reinterpret_cast<decltype(&aiImportFile)>(::dlsym(h, "aiImportFile"));
        r.release_import = reinterpret_cast<decltype(&aiReleaseImport)>(::dlsym(h, "aiReleaseImport"));
        r.error_string = reinterpret_cast<decltype(&aiGetErrorString)>(::dlsym(h, "aiGetErrorString"));
        if (!r.import_file || !r.release_import || !r.error_string) {
            r.import_file = nullptr;
            r.missing = "cannot load assimp (" RBCD_ASSIMP_SONAME "): it lacks aiImportFile, aiReleaseImport or aiGetErrorString";
        }
        return r;
    }();
    return a;
}
} // namespace

bool load_mesh_file_in_process(const std::string& path, Mesh& out, std::string& error) {
    if (!ply_file_ok(path, error)) return false;
    const AssimpC& ai = assimp_c();
    if (!ai.import_file) {
        error = ai.missing;
        return false;
    }
    const aiScene* s = ai.import_file(path.c_str(), aiProcess_Triangulate | aiProcess_JoinIdenticalVertices | aiProcess_SortByPType);
    struct Release {
        const AssimpC& ai;
        const aiScene* s;
        ~Release() {
            if (s) ai.release_import(s);
        }
    } release{ai, s};
    if (!s || !s->mRootNode || (s->mFlags & AI_SCENE_FLAGS_INCOMPLETE)) {
        // (assimp says why only when it returned no scene.)
        const char* why = s ? nullptr : ai.error_string();
        error = why ? why : "";
        if (error.empty()) error = "assimp could not import it";
        error = explain_import_error(path, error);
        return false;
    }
    out = Mesh{};
    append_node(s, s->mRootNode, aiMatrix4x4(), out);
    if (out.bad_index) {
        out = Mesh{};
        error = "a face refers to a vertex the mesh does not have";
        return false;
    }
    if (out.tris.empty()) {
        error = "it holds no triangles";
        return false;
    }
    for (const auto& v : out.verts) {
        if (!v.allFinite()) {
            error = "it holds a vertex that is not a finite number";
            return false;
        }
    }
    return true;
}

} // namespace rbcd::scene

namespace rbcd::scene {

// assimp is a large parser of hostile files that can abort or loop (fuzzing
// found both, docs/limits.md): it runs in a child process with a time limit,
// and the mesh comes back through a pipe. A crash or a timeout is an error
// naming the file, never the end of rbcd-sim.
namespace {
std::atomic<bool> abort_next_reader{false};
} // namespace

void abort_next_mesh_reader_for_test() { abort_next_reader = true; }

bool load_mesh_file(const std::string& path, Mesh& out, std::string& error, unsigned timeout_s) {
    const bool abort_reader = abort_next_reader.exchange(false);
    // Opened here, before the fork, never first in the child (a library
    // loaded after a fork can meet a lock another thread held then).
    if (!assimp_c().import_file) {
        error = assimp_c().missing;
        return false;
    }
    int p[2];
    if (::pipe2(p, O_CLOEXEC) != 0) return load_mesh_file_in_process(path, out, error);
    std::fflush(nullptr);
    const pid_t pid = ::fork();
    if (pid < 0) {
        ::close(p[0]);
        ::close(p[1]);
        return load_mesh_file_in_process(path, out, error);
    }
    if (pid == 0) {
        ::close(p[0]);
        // The parent's interrupt handlers remove its temporary outputs
        // (common/output_file.h); a signal meant for the reader must only end it.
        for (int sig : {SIGINT, SIGTERM, SIGHUP}) ::signal(sig, SIG_DFL);
        if (abort_reader) ::abort();
        ::alarm(timeout_s);
        Mesh m;
        std::string err;
        const std::uint8_t ok = load_mesh_file_in_process(path, m, err) ? 1 : 0;
        const std::uint64_t nv = m.verts.size(), nt = m.tris.size(), ne = err.size();
        bool w = !write_all(p[1], &ok, 1) && !write_all(p[1], &nv, 8) && !write_all(p[1], &nt, 8) &&
                 !write_all(p[1], &ne, 8) && !write_all(p[1], err.data(), err.size());
        for (const auto& v : m.verts) w = w && !write_all(p[1], v.data(), 3 * sizeof(double));
        if (nt) w = w && !write_all(p[1], m.tris.data(), nt * sizeof(m.tris[0]));
        ::_exit(w ? 0 : 1);
    }
    ::close(p[1]);
    std::string data;
    char buf[65536];
    for (;;) {
        const ssize_t k = ::read(p[0], buf, sizeof buf);
        if (k < 0 && errno == EINTR) continue;
        if (k <= 0) break;
        data.append(buf, static_cast<std::size_t>(k));
    }
    ::close(p[0]);
    int st = 0;
    while (::waitpid(pid, &st, 0) < 0 && errno == EINTR) {}
    if (WIFSIGNALED(st)) {
        error = WTERMSIG(st) == SIGALRM ? "the mesh reader (assimp) did not finish within " + std::to_string(timeout_s) + " s"
                                        : "the mesh reader (assimp) crashed (signal " + std::to_string(WTERMSIG(st)) + ")";
        return false;
    }
    std::size_t at = 0;
    auto take = [&](void* dst, std::size_t n) {
        if (data.size() - at < n) return false;
        std::memcpy(dst, data.data() + at, n);
        at += n;
        return true;
    };
    std::uint8_t ok = 0;
    std::uint64_t nv = 0, nt = 0, ne = 0;
    if (!WIFEXITED(st) || WEXITSTATUS(st) != 0 || !take(&ok, 1) || !take(&nv, 8) || !take(&nt, 8) || !take(&ne, 8) ||
        data.size() - at < ne) {
        error = "the mesh reader (assimp) failed";
        return false;
    }
    error.assign(data, at, ne);
    at += ne;
    if (!ok) return false;
    if ((data.size() - at) != nv * 3 * sizeof(double) + nt * sizeof(out.tris[0])) {
        error = "the mesh reader (assimp) failed";
        return false;
    }
    out = Mesh{};
    out.verts.resize(nv);
    for (auto& v : out.verts) take(v.data(), 3 * sizeof(double));
    out.tris.resize(nt);
    if (nt) take(out.tris.data(), nt * sizeof(out.tris[0]));
    return true;
}

} // namespace rbcd::scene
