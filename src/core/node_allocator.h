// The memory of EvidentialOcTreeNode (16 B each): fixed cells carved from 1 MiB chunks, so a node
// costs 16 B instead of the 32 B chunk glibc's malloc gives a 16-byte object (~50 MB of a
// 10-scan map). Threads allocate and free from a small cache of their own and trade cells with
// a locked global store in batches; a chunk whose cells are all free again is unmapped (one
// empty chunk is kept), so clearing or destroying a map gives its memory back to the system.
// Private to the core.
#pragma once

#include <cstddef>

namespace evidential_octomap {

class NodeAllocator {
 public:
  static constexpr size_t kCellBytes = 16;
  static constexpr size_t kChunkBytes = size_t(1) << 20;

  static void* allocate();  // one cell; throws std::bad_alloc
  static void deallocate(void* cell);
  // Gives the calling thread's cached cells back to the global store (also done at thread exit).
  static void flushThreadCache();

  struct Counters {
    size_t chunks = 0;     // chunks mapped (including the one empty chunk kept)
    size_t cells_out = 0;  // cells held by nodes or by the threads' caches
  };
  static Counters counters();
};

}  // namespace evidential_octomap
