// Debian's SystemC tells AddressSanitizer of each switch between its
// coroutines' stacks, but when a simulation returns to the main thread that
// thread's stack is left recorded as a coroutine's. LeakSanitizer's scan at
// exit then reads that range, and crashes ("Tracer caught signal 11") when
// its memory has gone since: 4% of rbcd-sim's runs of `--frames 0:0
// --threads 2` on a gzip trace did (docs/testing.md). MainStackForSanitizer
// records the thread's own stack again when it goes out of scope; nothing in
// a build without AddressSanitizer.
#pragma once

#if defined(__SANITIZE_ADDRESS__)
#include <pthread.h>
#include <sanitizer/common_interface_defs.h>

#include <cstddef>
#endif

namespace rbcd {

struct MainStackForSanitizer {
    MainStackForSanitizer() = default;
    MainStackForSanitizer(const MainStackForSanitizer&) = delete;
    MainStackForSanitizer& operator=(const MainStackForSanitizer&) = delete;
    ~MainStackForSanitizer() {
#if defined(__SANITIZE_ADDRESS__)
        pthread_attr_t a;
        if (::pthread_getattr_np(::pthread_self(), &a) != 0) return;
        void* bottom = nullptr;
        std::size_t size = 0;
        const bool ok = ::pthread_attr_getstack(&a, &bottom, &size) == 0;
        ::pthread_attr_destroy(&a);
        if (!ok) return;
        void* fake = nullptr;
        __sanitizer_start_switch_fiber(&fake, bottom, size);
        __sanitizer_finish_switch_fiber(fake, nullptr, nullptr);
#endif
    }
};

} // namespace rbcd
