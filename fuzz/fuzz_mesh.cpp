// The mesh loader as rbcd-sim runs it: load_mesh_file, which runs assimp in a
// child process (one fork per input), so that assimp aborting or looping is
// the loader's error, not the end of the fuzzer. The first byte picks the file
// extension assimp sees; the rest is the file.
//
// Coverage: the child's counters are its own and never reach libFuzzer, so
// when the child ended normally the same file is read again in this process
// (it does not crash there: the child just read it), which covers our code
// around assimp. The two results are not compared: on some malformed PLY files
// assimp's post-processing reads freed memory (valgrind), so two reads of one
// file can differ (found by comparing them). The child's mesh then goes
// through the mesh checks, as in a scene.
//
// Crashes in the child: a sanitizer report there (a memory error or undefined
// behaviour, in our code or caught in assimp by an interceptor) or a fault
// whose instruction is in this executable (our code) is a finding; an abort
// (assimp's assertions) or a fault inside a shared library (assimp) is the
// loader's error, as in rbcd-sim.
#include <dlfcn.h>
#include <pthread.h>
#include <signal.h>
#include <sys/mman.h>
#include <sys/resource.h>
#include <ucontext.h>
#include <unistd.h>

#include <cstdio>
#include <string>

#include "rbcd/fuzz/fuzz_util.h"
#include "rbcd/scene/mesh.h"
#include "rbcd/scene/mesh_check.h"

// Present only in sanitizer builds (the replay program may be built without).
extern "C" __attribute__((weak)) void __sanitizer_set_death_callback(void (*)(void));

namespace {

// Shared with the child: set there when the crash is a finding.
volatile int* g_child_finding = nullptr;
const void* g_exe_base = nullptr;   // where this executable (and so our code) is loaded
struct sigaction g_old[4];
constexpr int kFaults[4] = {SIGSEGV, SIGBUS, SIGFPE, SIGILL};
alignas(16) char g_altstack[1 << 16];

void child_death() { *g_child_finding = 1; }

void child_fault(int sig, siginfo_t*, void* ctx) {
    const auto* uc = static_cast<const ucontext_t*>(ctx);
#if defined(__x86_64__)
    const void* pc = reinterpret_cast<const void*>(uc->uc_mcontext.gregs[REG_RIP]);
#elif defined(__aarch64__)
    const void* pc = reinterpret_cast<const void*>(uc->uc_mcontext.pc);
#else
    const void* pc = nullptr;
    (void)uc;
#endif
    Dl_info info{};
    const bool library = pc && ::dladdr(pc, &info) && info.dli_fbase != g_exe_base;
    for (int i = 0; i < 4; ++i) {
        if (kFaults[i] != sig) continue;
        if (library) {
            signal(sig, SIG_DFL);
        } else {
            *g_child_finding = 1;
            ::sigaction(sig, &g_old[i], nullptr);   // the sanitizer's handler reports it with a stack
        }
    }
    // Returning re-runs the faulting instruction under the new disposition.
}

// In the loader's child only (the loader is this target's only fork). The
// handlers libFuzzer installed would catch assimp's abort() and the loader's
// alarm, write a crash or timeout file for this input and exit on their own.
void in_child() {
    ::signal(SIGABRT, SIG_DFL);
    ::signal(SIGALRM, SIG_DFL);
    const rlimit no_core{0, 0};
    ::setrlimit(RLIMIT_CORE, &no_core);
    if (__sanitizer_set_death_callback) __sanitizer_set_death_callback(child_death);
    stack_t ss{};
    if (::sigaltstack(nullptr, &ss) == 0 && (ss.ss_flags & SS_DISABLE)) {
        ss = stack_t{};
        ss.ss_sp = g_altstack;
        ss.ss_size = sizeof g_altstack;
        ::sigaltstack(&ss, nullptr);
    }
    struct sigaction sa {};
    sa.sa_sigaction = child_fault;
    sa.sa_flags = SA_SIGINFO | SA_ONSTACK;
    sigemptyset(&sa.sa_mask);
    for (int i = 0; i < 4; ++i) ::sigaction(kFaults[i], &sa, &g_old[i]);
}

void set_up() {
    void* p = ::mmap(nullptr, sizeof(int), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
    if (p == MAP_FAILED) std::abort();
    g_child_finding = static_cast<volatile int*>(p);
    Dl_info info{};
    if (!::dladdr(reinterpret_cast<const void*>(&set_up), &info)) std::abort();
    g_exe_base = info.dli_fbase;
    if (::pthread_atfork(nullptr, nullptr, in_child) != 0) std::abort();
}

} // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    static const bool ready = (set_up(), true);
    (void)ready;
    if (size < 1) return 0;
    static const char* const ext[] = {".obj", ".ply", ".stl", ".off", ".gltf", ".glb", ".dae", ".3ds"};
    const std::string path = "/tmp/rbcd-fuzz-mesh-" + std::to_string(::getpid()) + ext[data[0] & 7];
    {
        std::FILE* f = std::fopen(path.c_str(), "wb");
        if (!f) std::abort();
        std::fwrite(data + 1, 1, size - 1, f);
        std::fclose(f);
    }
    using namespace rbcd::scene;
    *g_child_finding = 0;
    Mesh m;
    std::string err;
    // 3 s: a child that loops is stopped before libFuzzer's -timeout (10 s in scripts/fuzz.sh).
    const bool ok = load_mesh_file(path, m, err, 3);
    if (*g_child_finding) rbcd::fuzz::finding("the mesh reader's child crashed in our code or under a sanitizer (report above)");
    // The loader's own words for a child that crashed, timed out or sent nothing usable.
    const bool child_ended = ok || err.rfind("the mesh reader (assimp) ", 0) != 0;
    if (child_ended) {
        // For coverage only: the two reads may differ (see the top).
        Mesh here;
        std::string here_err;
        load_mesh_file_in_process(path, here, here_err);
    }
    ::unlink(path.c_str());
    if (!ok) return 0;
    for (const auto& t : m.tris)
        for (auto i : t)
            if (i >= m.verts.size()) rbcd::fuzz::finding("triangle index out of range");
    // A small pair budget: the search, not its length, is what is fuzzed.
    const MeshCheck c = check_mesh(m, 100000);
    if (c.self_intersecting && (c.tri_a >= m.tris.size() || c.tri_b >= m.tris.size() || c.tri_a == c.tri_b))
        rbcd::fuzz::finding("mesh check names a triangle pair the mesh does not have");
    if (c.inside_out && !c.closed) rbcd::fuzz::finding("mesh check: inside out but not closed");
    const bool flagged = c.boundary_edges || c.nonmanifold_edges || c.misoriented_edges || c.inside_out || c.self_intersecting;
    if (flagged == c.problems().empty()) rbcd::fuzz::finding("mesh check: problems() disagrees with the counts");
    return 0;
}
