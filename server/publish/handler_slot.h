#pragma once
// Memory for one posted handler at a time, so that posting to the io thread from a thread that
// does not run the io_context (the pipeline thread, every frame) allocates nothing: asio takes a
// posted operation's memory from the handler's associated allocator, and the default one goes
// to the heap on such threads. The owner keeps at most one handler in the slot at a time; a
// second one while the slot is busy (not expected) gets heap memory instead of failing.
//
// The allocator shares ownership of the slot: asio gives the memory back after destroying the
// handler, which may hold the last reference to the slot's owner.

#include <atomic>
#include <cstddef>
#include <memory>
#include <new>

namespace skinstream::server {

class HandlerSlot {
 public:
  static constexpr size_t kBytes = 256;  // a posted lambda with a shared_ptr takes about 80

  void* take(size_t bytes) {
    if (bytes <= kBytes && !busy_.exchange(true, std::memory_order_acquire)) return storage_;
    return ::operator new(bytes);
  }
  void give_back(void* memory) noexcept {
    if (memory == storage_)
      busy_.store(false, std::memory_order_release);
    else
      ::operator delete(memory);
  }
  bool busy() const { return busy_.load(); }

 private:
  alignas(std::max_align_t) unsigned char storage_[kBytes];
  std::atomic<bool> busy_{false};
};

template <typename T>
class HandlerSlotAllocator {
 public:
  using value_type = T;

  explicit HandlerSlotAllocator(std::shared_ptr<HandlerSlot> slot) noexcept : slot_(std::move(slot)) {}
  template <typename U>
  HandlerSlotAllocator(const HandlerSlotAllocator<U>& other) noexcept : slot_(other.slot()) {}

  T* allocate(size_t n) { return static_cast<T*>(slot_->take(n * sizeof(T))); }
  void deallocate(T* memory, size_t) noexcept { slot_->give_back(memory); }

  const std::shared_ptr<HandlerSlot>& slot() const noexcept { return slot_; }
  template <typename U>
  bool operator==(const HandlerSlotAllocator<U>& other) const noexcept {
    return slot_ == other.slot();
  }
  template <typename U>
  bool operator!=(const HandlerSlotAllocator<U>& other) const noexcept {
    return slot_ != other.slot();
  }

 private:
  std::shared_ptr<HandlerSlot> slot_;
};

// A handler that asio allocates in `slot` (Boost 1.74 has no bind_allocator: asio finds the
// allocator through the handler's allocator_type and get_allocator()).
template <typename Function>
struct SlotHandler {
  using allocator_type = HandlerSlotAllocator<void>;
  std::shared_ptr<HandlerSlot> slot;
  Function function;

  allocator_type get_allocator() const noexcept { return allocator_type(slot); }
  void operator()() { function(); }
};

template <typename Function>
SlotHandler<Function> in_slot(std::shared_ptr<HandlerSlot> slot, Function function) {
  return {std::move(slot), std::move(function)};
}

}  // namespace skinstream::server
