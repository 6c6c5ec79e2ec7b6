// ThreadSanitizer build only (preset tsan force-includes this file into every source).
//
// Debian's libtbb is not built with ThreadSanitizer, so the happens-before edges its
// scheduler makes (a task's spawn before its execution, every task before the end of
// the wait) are invisible to TSan, and every parallel_for would be reported as racing
// with the code around it. This overload of tbb::parallel_for for a blocked_range of
// any index type (with or without a static, simple or auto partitioner: the forms metariver calls; and
// parallel_invoke of two functions) states exactly the guarantees TBB
// gives, as TSan annotations: everything before the call happens before every chunk of
// the loop, and every chunk happens before the call returns. Chunks are NOT ordered with each other,
// so a race between two chunks (the bugs TSan is here for) is still reported.
// What is left are TBB's own task objects, written by one thread and read by another
// through the uninstrumented scheduler: tests/sanitizers/tsan.supp suppresses races
// whose top frame is inside tbb::detail, never a frame of metariver.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/partitioner.h>

#include <cstddef>

extern "C" void __tsan_acquire(void* addr);
extern "C" void __tsan_release(void* addr);

namespace tbb {

/// The loop with its edges. One overload per form metariver calls follows: without a
/// partitioner (TBB's default, __TBB_DEFAULT_PARTITIONER), and with a static
/// (src/particles/parallel_blocks.h), simple (the shallow-water sweep's rows) or auto one;
/// a template over the partitioner would be no more specialised than TBB's own overloads
/// and the call ambiguous.
template <typename Value, typename Body, typename Partitioner>
void annotated_parallel_for(const blocked_range<Value>& range, const Body& body, const Partitioner& part) {
    char before = 0, after = 0;
    __tsan_release(&before);
    detail::d1::parallel_for(
        range,
        [&](const blocked_range<Value>& r) {
            __tsan_acquire(&before);
            body(r);
            __tsan_release(&after);
        },
        part);
    __tsan_acquire(&after);
}
template <typename Value, typename Body>
void parallel_for(const blocked_range<Value>& range, const Body& body) {
    annotated_parallel_for(range, body, __TBB_DEFAULT_PARTITIONER());
}
template <typename Value, typename Body>
void parallel_for(const blocked_range<Value>& range, const Body& body, const static_partitioner& part) {
    annotated_parallel_for(range, body, part);
}
template <typename Value, typename Body>
void parallel_for(const blocked_range<Value>& range, const Body& body, const simple_partitioner& part) {
    annotated_parallel_for(range, body, part);
}
template <typename Value, typename Body>
void parallel_for(const blocked_range<Value>& range, const Body& body, const auto_partitioner& part) {
    annotated_parallel_for(range, body, part);
}

/// And for two functions run side by side (the hybrid's grid and particles): everything
/// before the call happens before both, both before the return; the two are NOT ordered
/// with each other, so a race between them is still reported.
template <typename F0, typename F1>
void parallel_invoke(F0&& f0, F1&& f1) {
    char before = 0, after = 0;
    __tsan_release(&before);
    detail::d1::parallel_invoke(
        [&] {
            __tsan_acquire(&before);
            f0();
            __tsan_release(&after);
        },
        [&] {
            __tsan_acquire(&before);
            f1();
            __tsan_release(&after);
        });
    __tsan_acquire(&after);
}

}  // namespace tbb
