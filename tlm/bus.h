// The width every socket of the model is declared with. A TLM-2.0 socket's
// BUSWIDTH is a template argument that must match at bind time; the model
// moves whole 16-byte records and times transfers itself (memory.bytes_per_cycle),
// so the figure only has to agree with the platform's sockets. Platforms with
// another width put an adapter (or a router declared with both) in between.
#pragma once

namespace rbcd {

constexpr unsigned kBusWidth = 64;   // bits

} // namespace rbcd
