// Named counters of a block's stats struct, enumerated once and visited both
// ways: read (reports, VCD) and written (rbcd-merge rebuilds a run's counters
// from its stats JSON). Every counter is a uint64_t; its merge rule across
// frame ranges follows from its name (docs/stats.md): `max_*` is a maximum,
// `*_cycle` a point in time, everything else a sum.
//
//   struct Stats {
//       std::uint64_t hits = 0;
//       RBCD_STATS_VISITOR { RBCD_STAT(f, s, hits, "hit records written"); }
//   };
//   stats.for_each([](const char* name, std::uint64_t v, const char* desc) {...});
//   stats.for_each([](const char* name, std::uint64_t& v, const char*) { v = 0; });
#pragma once

#define RBCD_STAT(f, s, name, desc) f(#name, (s).name, desc)

#define RBCD_STATS_VISITOR                                                   \
    template <class F> void for_each(F f) const { visit(*this, f); }         \
    template <class F> void for_each(F f) { visit(*this, f); }               \
    template <class S, class F> static void visit(S& s, F f)
