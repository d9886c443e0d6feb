#include "rbcd/cpu/instruction_count.h"

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <sys/mman.h>
#include <sys/stat.h>
#include <LinearMath/btAlignedAllocator.h>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

#include "rbcd/common/errors.h"

#if __has_include(<valgrind/callgrind.h>)
#include <valgrind/callgrind.h>
#define RBCD_HAVE_CALLGRIND 1
#else
#define RBCD_HAVE_CALLGRIND 0
#endif

namespace rbcd::cpucd {

namespace {

// Set for the child: where callgrind writes its dumps. Its presence, with
// RUNNING_ON_VALGRIND, tells the child it is the counting run.
constexpr const char* kDumpEnv = "RBCD_CPUCD_CALLGRIND_OUT";

pid_t g_child = 0;
extern "C" void forward_signal(int sig) {
    if (g_child > 0) ::kill(g_child, sig);
}

bool valgrind_on_path() {
    const char* path = std::getenv("PATH");
    std::string p = path ? path : "/usr/bin:/bin";
    std::size_t b = 0;
    while (b <= p.size()) {
        std::size_t e = p.find(':', b);
        if (e == std::string::npos) e = p.size();
        const std::string dir = e > b ? p.substr(b, e - b) : ".";
        if (::access((dir + "/valgrind").c_str(), X_OK) == 0) return true;
        b = e + 1;
    }
    return false;
}

// One reserved address range, carved from its start; freed blocks are kept
// on a list per size class and reused last in, first out. No locking: the
// detection is single-threaded.
class DeterministicHeap {
public:
    void* alloc(std::size_t size, std::size_t align) {
        if (align < kHeader) align = kHeader;
        const std::size_t need = size + align;   // room to align the payload after the header
        const unsigned cls = size_class(need);
        char* block;
        if (free_[cls]) {
            block = static_cast<char*>(free_[cls]);
            free_[cls] = *reinterpret_cast<void**>(block);
        } else {
            const std::size_t bytes = class_bytes(cls);
            if (!base_) reserve();
            if (used_ + bytes > kReserve) throw std::bad_alloc();
            block = base_ + used_;
            used_ += bytes;
        }
        char* p = block + kHeader;
        p += (align - reinterpret_cast<std::uintptr_t>(p) % align) % align;
        Header* h = reinterpret_cast<Header*>(p - kHeader);
        h->block = block;
        h->cls = cls;
        return p;
    }
    void release(void* p) {
        if (!p) return;
        const Header* h = reinterpret_cast<const Header*>(static_cast<char*>(p) - kHeader);
        char* block = h->block;
        const unsigned cls = h->cls;
        *reinterpret_cast<void**>(block) = free_[cls];
        free_[cls] = block;
    }

private:
    struct Header {
        char* block;
        std::uint64_t cls;
    };
    static constexpr std::size_t kHeader = sizeof(Header);   // 16
    // Address space only (MAP_NORESERVE): pages are backed when touched.
    static constexpr std::size_t kReserve = std::size_t(16) << 30;
    static constexpr unsigned kSmall = 64;   // classes of 16 bytes up to 1 KiB, then powers of two
    static unsigned size_class(std::size_t n) {
        if (n <= kSmall * 16) return unsigned((n + 15) / 16);
        unsigned k = 11;
        while ((std::size_t(1) << k) < n) ++k;
        return kSmall + k;
    }
    static std::size_t class_bytes(unsigned cls) {
        return cls <= kSmall ? std::size_t(cls) * 16 : std::size_t(1) << (cls - kSmall);
    }
    void reserve() {
        void* m = ::mmap(nullptr, kReserve, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
        if (m == MAP_FAILED) throw std::bad_alloc();
        base_ = static_cast<char*>(m);
    }
    char* base_ = nullptr;
    std::size_t used_ = 0;
    void* free_[kSmall + 64] = {};
};

DeterministicHeap g_heap;
void* heap_alloc_aligned(std::size_t size, int align) { return g_heap.alloc(size, std::size_t(align)); }
void heap_free_aligned(void* p) { g_heap.release(p); }
void* heap_alloc(std::size_t size) { return g_heap.alloc(size, 16); }
void heap_free(void* p) { g_heap.release(p); }

} // namespace

void use_deterministic_bullet_heap() {
    btAlignedAllocSetCustom(heap_alloc, heap_free);
    btAlignedAllocSetCustomAligned(heap_alloc_aligned, heap_free_aligned);
}

bool callgrind_compiled_in() { return RBCD_HAVE_CALLGRIND; }

bool counting_under_callgrind() {
#if RBCD_HAVE_CALLGRIND
    return RUNNING_ON_VALGRIND && std::getenv(kDumpEnv) != nullptr;
#else
    return false;
#endif
}

int run_under_callgrind(int argc, char* argv[]) {
#ifdef __SANITIZE_ADDRESS__
    // ASan's shadow memory and valgrind's own address space cannot coexist.
    throw InputError("--count-instructions: this rbcd-cpucd was built with AddressSanitizer (RBCD_SANITIZE), which "
                     "valgrind cannot run; count with a build without it");
#endif
    if (!callgrind_compiled_in())
        throw InputError("--count-instructions: this rbcd-cpucd was built without valgrind/callgrind.h "
                         "(Debian's valgrind, scripts/setup.sh --eval; then rebuild)");
    if (!valgrind_on_path())
        throw InputError("--count-instructions: valgrind not found on PATH (Debian's valgrind, scripts/setup.sh --eval)");
    char exe[4096];
    const ssize_t n = ::readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (n <= 0) throw std::runtime_error("cannot read /proc/self/exe");
    exe[n] = 0;
    const char* tmp = std::getenv("TMPDIR");
    std::string dir = std::string(tmp && *tmp ? tmp : "/tmp") + "/rbcd-cpucd-count.XXXXXX";
    if (!::mkdtemp(dir.data())) throw std::runtime_error("mkdtemp " + dir + ": " + std::strerror(errno));
    const std::string prefix = dir + "/cg";

    // Collection off until the first section; instrumentation off until the
    // first frame's detection (CallgrindCounter::instrument): loading runs at
    // valgrind's uninstrumented speed.
    std::vector<std::string> args = {"valgrind", "--tool=callgrind", "-q", "--vgdb=no", "--collect-atstart=no",
                                     "--instr-atstart=no", "--compress-strings=no", "--compress-pos=no",
                                     "--callgrind-out-file=" + prefix, exe};
    for (int i = 1; i < argc; ++i) args.emplace_back(argv[i]);
    std::vector<char*> av;
    for (auto& a : args) av.push_back(a.data());
    av.push_back(nullptr);

    struct sigaction sa {}, old_int {}, old_term {}, old_hup {};
    sa.sa_handler = forward_signal;
    ::sigemptyset(&sa.sa_mask);
    ::sigaction(SIGINT, &sa, &old_int);
    ::sigaction(SIGTERM, &sa, &old_term);
    ::sigaction(SIGHUP, &sa, &old_hup);
    const pid_t pid = ::fork();
    if (pid < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
    if (pid == 0) {
        ::setenv(kDumpEnv, prefix.c_str(), 1);
        // Every symbol bound at start: lazily, the dynamic linker's lookup
        // would be counted in whichever section first calls a function.
        ::setenv("LD_BIND_NOW", "1", 1);
        ::execvp("valgrind", av.data());
        std::fprintf(stderr, "rbcd-cpucd: --count-instructions: cannot run valgrind: %s\n", std::strerror(errno));
        ::_exit(2);
    }
    g_child = pid;
    int status = 0;
    while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    g_child = 0;
    ::sigaction(SIGINT, &old_int, nullptr);
    ::sigaction(SIGTERM, &old_term, nullptr);
    ::sigaction(SIGHUP, &old_hup, nullptr);
    // Whatever the child left (it removes each dump it reads; callgrind's
    // final, empty dump is written at its exit).
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
    if (WIFEXITED(status)) return WEXITSTATUS(status);
    return 1;
}

CallgrindCounter::CallgrindCounter() {
    const char* p = std::getenv(kDumpEnv);
    prefix_ = p ? p : "";
}

void CallgrindCounter::instrument(bool on) {
#if RBCD_HAVE_CALLGRIND
    if (on) CALLGRIND_START_INSTRUMENTATION;
    else CALLGRIND_STOP_INSTRUMENTATION;
#else
    (void)on;
#endif
}

void CallgrindCounter::start() {
#if RBCD_HAVE_CALLGRIND
    CALLGRIND_TOGGLE_COLLECT;
#endif
}

std::uint64_t CallgrindCounter::stop(Section) {
#if RBCD_HAVE_CALLGRIND
    CALLGRIND_TOGGLE_COLLECT;
    CALLGRIND_DUMP_STATS;
#endif
    const std::string path = prefix_ + "." + std::to_string(++dumps_);
    std::ifstream f(path);
    if (!f) throw std::runtime_error("--count-instructions: no callgrind dump at " + path);
    const CallgrindCounts c = parse_callgrind_dump(f);
    f.close();
    std::remove(path.c_str());
    if (!c.has_total) throw std::runtime_error("--count-instructions: " + path + ": no totals line");
    return c.total - c.allocator;
}

bool is_allocator_function(const std::string& name) {
    // The entry points only: what they call is inside their inclusive cost.
    static const char* const exact[] = {"malloc", "free", "realloc", "calloc", "cfree", "memalign", "posix_memalign",
                                        "aligned_alloc", "valloc", "pvalloc", "__libc_malloc", "__libc_free",
                                        "__libc_realloc", "__libc_calloc", "__libc_memalign", "__posix_memalign",
                                        "_mid_memalign"};
    for (const char* e : exact)
        if (name == e) return true;
    return name.rfind("operator new", 0) == 0 || name.rfind("operator delete", 0) == 0;
}

CallgrindCounts parse_callgrind_dump(std::istream& in) {
    CallgrindCounts c;
    std::string line, fn, cfn;
    bool cost_of_call = false;   // the line after calls= is the call's inclusive cost
    const auto last_number = [](const std::string& l) {
        const std::size_t sp = l.find_last_of(' ');
        return std::strtoull(l.c_str() + (sp == std::string::npos ? 0 : sp + 1), nullptr, 10);
    };
    while (std::getline(in, line)) {
        if (cost_of_call) {
            cost_of_call = false;
            if (!is_allocator_function(fn) && is_allocator_function(cfn)) c.allocator += last_number(line);
            continue;
        }
        if (line.rfind("fn=", 0) == 0) {
            fn = line.substr(3);
        } else if (line.rfind("cfn=", 0) == 0) {
            cfn = line.substr(4);
        } else if (line.rfind("calls=", 0) == 0) {
            cost_of_call = true;
        } else if (line.rfind("totals:", 0) == 0 || line.rfind("summary:", 0) == 0) {
            c.total = std::strtoull(line.c_str() + line.find(':') + 1, nullptr, 10);
            c.has_total = true;
        }
    }
    return c;
}

} // namespace rbcd::cpucd
