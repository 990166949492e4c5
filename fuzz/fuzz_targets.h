// Fuzz targets of evidential_octomap, shared by the libFuzzer entry points (fuzz_*.cpp, clang)
// and the deterministic replay harness (replay_main.cpp, any compiler, run by ctest).
//
// Every target takes arbitrary bytes. It returns normally when the library behaved: a clean
// rejection (nullptr, readError(), std::runtime_error) or a successful read whose result passes
// the invariants below. A broken invariant calls fuzzFail(), which prints what broke and aborts,
// so libFuzzer, the sanitizers and the replay harness all see it as a crash.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

namespace evidential_octomap {
namespace fuzz {

// The .ot reader: octomap::AbstractOcTree::read on the bytes, then (our tree only) every query,
// leaf iteration, inner-node update, copy, write/read round trip (must be byte-identical), .bt
// and ColorOcTree export, one small scan insert, and loadMap() on the same bytes, which must
// agree with the generic reader (success <=> success) and fail only with std::runtime_error.
int fuzzOtReader(const uint8_t* data, size_t size);

// ClassTable::load on the bytes as a YAML file: returns a valid table or throws
// std::runtime_error; nothing else.
int fuzzClassTable(const uint8_t* data, size_t size);

// The core calls behind the node's services and settings, on a small map, in the order and with
// the values the bytes give (every float may be NaN, inf or huge): query / nodeAt (~query),
// clearBox (~clear_bbx), setSensorModel and setConfig + a scan (~params, dynamic_reconfigure),
// saveMap + loadMap (~save_map, ~load_map). A refused request must change nothing; an accepted
// one must leave a map whose every readout is an opinion and which saves and loads again.
int fuzzMapServices(const uint8_t* data, size_t size);

// Silences octomap's and our own diagnostics on std::cerr (thousands of expected
// "corrupt file" lines per second); sanitizer reports are written to fd 2 directly.
void silenceDiagnostics();
// Also points fd 2 at /dev/null (OctoMap prints some errors with fprintf), keeping fuzzFail and
// sanitizer reports on the original stderr. For the replay harness; libFuzzer has
// -close_fd_mask=2 for the same purpose and needs fd 2 for its own output.
void silenceStderr();

// fuzzOtReader inserts a scan into one loaded map in four (chosen by a hash of the input) to
// keep libFuzzer fast; the replay harness makes it do so for every input.
void setAlwaysHeavy(bool always);

// Recomputes the trailing CRC-32 of a format-2 .ot data section in place (no-op for anything
// else), so that mutations reach the parser behind the checksum instead of stopping at it.
void resealOtChecksum(uint8_t* data, size_t size);

[[noreturn]] void fuzzFail(const std::string& what);

}  // namespace fuzz
}  // namespace evidential_octomap
