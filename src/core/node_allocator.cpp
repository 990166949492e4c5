#include "node_allocator.h"

#include <sys/mman.h>

#include <cstdint>
#include <mutex>
#include <new>

// LeakSanitizer scans the heap, globals, stacks and TLS, not mmap'd memory: without the chunks
// registered as root regions, the child arrays and payloads that only nodes point to would be
// reported as leaked for every tree still alive at exit.
#if defined(__SANITIZE_ADDRESS__)
#define EVIDENTIAL_OCTOMAP_LSAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(leak_sanitizer)
#define EVIDENTIAL_OCTOMAP_LSAN 1
#endif
#endif
#ifdef EVIDENTIAL_OCTOMAP_LSAN
#include <sanitizer/lsan_interface.h>
#endif

namespace evidential_octomap {
namespace {

struct Cell {
  Cell* next;
};

// A chunk starts with this header, aligned to kChunkBytes, so a cell finds its chunk by masking.
struct Chunk {
  Chunk* prev;
  Chunk* next;
  Cell* free;      // cells given back
  uint32_t fresh;  // cells [fresh, kCells) never handed out: their pages are not touched yet
  uint32_t live;   // cells handed out and not given back
  bool listed;     // in the list of chunks with cells to hand out
};
constexpr uint32_t kHeaderCells =
    (sizeof(Chunk) + NodeAllocator::kCellBytes - 1) / NodeAllocator::kCellBytes;
constexpr uint32_t kCells = NodeAllocator::kChunkBytes / NodeAllocator::kCellBytes;

// Cells a thread takes at a time, and the most it keeps before giving a batch back.
constexpr uint32_t kBatch = 64;
constexpr uint32_t kMaxCached = 2 * kBatch;

Chunk* chunkOf(void* cell) {
  return reinterpret_cast<Chunk*>(reinterpret_cast<uintptr_t>(cell) &
                                  ~uintptr_t(NodeAllocator::kChunkBytes - 1));
}
Cell* cellAt(Chunk* chunk, uint32_t i) {
  return reinterpret_cast<Cell*>(reinterpret_cast<char*>(chunk) +
                                 size_t(i) * NodeAllocator::kCellBytes);
}

// An aligned chunk straight from the system: mapped twice its size, the unaligned ends unmapped.
Chunk* mapChunk() {
  constexpr size_t size = NodeAllocator::kChunkBytes;
  void* raw = mmap(nullptr, 2 * size, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
  if (raw == MAP_FAILED) throw std::bad_alloc();
  const uintptr_t begin = reinterpret_cast<uintptr_t>(raw);
  const uintptr_t aligned = (begin + size - 1) & ~uintptr_t(size - 1);
  if (aligned > begin) munmap(raw, aligned - begin);
  if (aligned + size < begin + 2 * size) {
    munmap(reinterpret_cast<void*>(aligned + size), begin + 2 * size - (aligned + size));
  }
#ifdef EVIDENTIAL_OCTOMAP_LSAN
  __lsan_register_root_region(reinterpret_cast<void*>(aligned), size);
#endif
  return reinterpret_cast<Chunk*>(aligned);
}

void unmapChunk(Chunk* chunk) {
#ifdef EVIDENTIAL_OCTOMAP_LSAN
  __lsan_unregister_root_region(chunk, NodeAllocator::kChunkBytes);
#endif
  munmap(chunk, NodeAllocator::kChunkBytes);
}

class GlobalStore {
 public:
  // Links up to `count` cells into a list (at least one, or throws std::bad_alloc), returns its
  // head and sets *taken.
  Cell* take(uint32_t count, uint32_t* taken) {
    std::lock_guard<std::mutex> lock(mutex_);
    Cell* head = nullptr;
    uint32_t i = 0;
    for (; i < count; ++i) {
      if (!available_) {
        try {
          addChunk();
        } catch (const std::bad_alloc&) {
          if (i == 0) throw;
          break;
        }
      }
      Chunk* chunk = available_;
      Cell* cell = chunk->free;
      if (cell) {
        chunk->free = cell->next;
      } else {
        cell = cellAt(chunk, chunk->fresh++);
      }
      ++chunk->live;
      if (!chunk->free && chunk->fresh == kCells) unlink(chunk);
      cell->next = head;
      head = cell;
    }
    cells_out_ += i;
    *taken = i;
    return head;
  }

  // Takes back the first `count` cells of the list at `head`; returns the rest.
  Cell* give(Cell* head, uint32_t count) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (uint32_t i = 0; i < count; ++i) {
      Cell* cell = head;
      head = cell->next;
      Chunk* chunk = chunkOf(cell);
      cell->next = chunk->free;
      chunk->free = cell;
      if (!chunk->listed) link(chunk);
      if (--chunk->live == 0) retire(chunk);
    }
    cells_out_ -= count;
    return head;
  }

  NodeAllocator::Counters counters() {
    std::lock_guard<std::mutex> lock(mutex_);
    NodeAllocator::Counters c;
    c.chunks = chunks_;
    c.cells_out = cells_out_;
    return c;
  }

 private:
  void addChunk() {
    Chunk* chunk = spare_;
    spare_ = nullptr;
    if (!chunk) {
      chunk = mapChunk();
      ++chunks_;
    }
    *chunk = Chunk{nullptr, nullptr, nullptr, kHeaderCells, 0, false};
    link(chunk);
  }
  void link(Chunk* chunk) {
    chunk->prev = nullptr;
    chunk->next = available_;
    if (available_) available_->prev = chunk;
    available_ = chunk;
    chunk->listed = true;
  }
  void unlink(Chunk* chunk) {
    (chunk->prev ? chunk->prev->next : available_) = chunk->next;
    if (chunk->next) chunk->next->prev = chunk->prev;
    chunk->listed = false;
  }
  // A chunk with no cell out: kept as the spare (its pages stay, ready for reuse) or unmapped.
  void retire(Chunk* chunk) {
    unlink(chunk);
    if (!spare_) {
      spare_ = chunk;
      return;
    }
    unmapChunk(chunk);
    --chunks_;
  }

  std::mutex mutex_;
  Chunk* available_ = nullptr;  // chunks with free or fresh cells
  Chunk* spare_ = nullptr;      // an empty chunk, not in the list
  size_t chunks_ = 0;
  size_t cells_out_ = 0;
};

// Never destroyed: threads may give cells back after static destructors ran.
GlobalStore& store() {
  static GlobalStore* global = new GlobalStore();
  return *global;
}

struct ThreadCache {
  Cell* head = nullptr;
  uint32_t count = 0;
  ~ThreadCache() { flush(); }
  void flush() {
    if (count > 0) store().give(head, count);
    head = nullptr;
    count = 0;
  }
};
thread_local ThreadCache cache;

}  // namespace

void* NodeAllocator::allocate() {
  ThreadCache& c = cache;
  if (c.count == 0) c.head = store().take(kBatch, &c.count);
  Cell* cell = c.head;
  c.head = cell->next;
  --c.count;
  return cell;
}

void NodeAllocator::deallocate(void* p) {
  ThreadCache& c = cache;
  Cell* cell = static_cast<Cell*>(p);
  cell->next = c.head;
  c.head = cell;
  if (++c.count > kMaxCached) {
    c.head = store().give(c.head, kBatch);
    c.count -= kBatch;
  }
}

void NodeAllocator::flushThreadCache() { cache.flush(); }

NodeAllocator::Counters NodeAllocator::counters() { return store().counters(); }

}  // namespace evidential_octomap
