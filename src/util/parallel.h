// parallel.h — parallelFor: a loop body run on several threads (the calling one included), for the host
// work over big arrays (flattening meshes, the BVH builder's items, the leaf blocks), where both the
// independent items and the first touch of fresh pages (the kernel zeroes each one) scale with threads.
#pragma once
#include <algorithm>
#include <atomic>
#include <exception>
#include <system_error>
#include <thread>
#include <vector>

namespace clrt {

// Runs body(k) for k = 0 .. count - 1 on up to maxThreads threads (0: every hardware thread), this one
// included. Items are handed out one at a time: give it chunks of work, not single elements. The first
// exception a body throws stops the others (after their current item) and is rethrown here; when no
// thread can be started the calling thread does everything.
template <class Body>
void parallelFor(size_t count, const Body& body, size_t maxThreads = 0) {
    std::atomic<size_t> next{0};
    size_t threads = std::max(1u, std::thread::hardware_concurrency());
    if (maxThreads) threads = std::min(threads, maxThreads);
    threads = std::max<size_t>(1, std::min(threads, count));
    std::vector<std::exception_ptr> errors(threads);
    auto worker = [&](size_t t) {
        try {
            for (size_t k; (k = next++) < count;) body(k);
        } catch (...) {
            errors[t] = std::current_exception();
            next = count;  // the others stop too
        }
    };
    std::vector<std::thread> pool;
    try {
        for (size_t t = 1; t < threads; ++t) pool.emplace_back(worker, t);
    } catch (const std::system_error&) {  // fewer threads to be had: the others (and this one) do it
    }
    worker(0);
    for (std::thread& t : pool) t.join();
    for (const std::exception_ptr& e : errors)
        if (e) std::rethrow_exception(e);
}

}  // namespace clrt
