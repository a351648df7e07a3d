#include "server/publish/handler_slot.h"

#include <gtest/gtest.h>

#include <atomic>
#include <thread>

#include "server/asio.h"
#include "support/allocation_counter.h"

namespace skinstream::server {
namespace {

// A thread that does not run the io_context (as the pipeline thread) posts one handler at a
// time through the slot: no heap allocation, every handler runs, the slot is free after each.
TEST(HandlerSlot, PostingFromAnotherThreadAllocatesNothing) {
  asio::io_context io;
  auto guard = asio::make_work_guard(io);
  std::thread io_thread([&] { io.run(); });
  const auto slot = std::make_shared<HandlerSlot>();
  std::atomic<int> ran{0};
  size_t allocations = 0;
  {
    test::CountAllocations counter;
    for (int i = 0; i < 1000; ++i) {
      asio::post(io, in_slot(slot, [&ran] { ran.fetch_add(1); }));
      while (ran.load() != i + 1) std::this_thread::yield();
      while (slot->busy()) std::this_thread::yield();  // given back just before the handler ran
    }
    allocations = counter.count();
  }
  EXPECT_EQ(allocations, 0u);
  EXPECT_EQ(ran.load(), 1000);
  // The same posts without the slot do allocate on this thread: what the slot is for.
  {
    test::CountAllocations counter;
    asio::post(io, [&ran] { ran.fetch_add(1); });
    allocations = counter.count();
  }
  EXPECT_GT(allocations, 0u);
  guard.reset();
  io_thread.join();
}

// A second handler while the first is still queued gets heap memory: both run, nothing is
// overwritten, and the slot is free again afterwards.
TEST(HandlerSlot, SecondHandlerWhileBusyRunsFromTheHeap) {
  asio::io_context io;
  const auto slot = std::make_shared<HandlerSlot>();
  std::vector<int> order;
  asio::post(io, in_slot(slot, [&order] { order.push_back(1); }));
  EXPECT_TRUE(slot->busy());
  asio::post(io, in_slot(slot, [&order] { order.push_back(2); }));
  io.run();
  EXPECT_EQ(order, (std::vector<int>{1, 2}));
  EXPECT_FALSE(slot->busy());
}

// The handler may hold the last reference to the slot's owner: asio gives the memory back
// after destroying the handler, and the allocator keeps the slot alive until then.
TEST(HandlerSlot, HandlerHoldingTheLastReferenceToTheOwner) {
  struct Owner {
    std::shared_ptr<HandlerSlot> slot = std::make_shared<HandlerSlot>();
  };
  asio::io_context io;
  std::weak_ptr<HandlerSlot> watch;
  bool ran = false;
  {
    auto owner = std::make_shared<Owner>();
    watch = owner->slot;
    asio::post(io, in_slot(owner->slot, [owner, &ran] { ran = owner->slot->busy() == false; }));
  }
  EXPECT_FALSE(watch.expired());
  io.run();
  EXPECT_TRUE(ran);  // the memory was given back before the handler ran
  EXPECT_TRUE(watch.expired());
}

}  // namespace
}  // namespace skinstream::server
