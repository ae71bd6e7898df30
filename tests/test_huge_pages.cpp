// util/huge_pages: HostArray storage is 2 MiB aligned from kHugeMinBytes up, and inside a HugeRecycling
// scope a freed block serves the next request it holds (the same pages, the tail past the request given
// back), a request no kept block holds frees them all, and the scope's end frees what is left.
#include <catch.hpp>

#include <cstdint>
#include <cstring>

#include "util/huge_pages.h"

using namespace clrt;

TEST_CASE("huge pages: blocks are recycled only inside a HugeRecycling scope", "[huge_pages]") {
    const size_t big = size_t(8) << 20, mid = size_t(5) << 20, small = size_t(3) << 20;
    SECTION("outside a scope a freed block goes back") {
        const size_t before = hugeRecycledBytes();
        void* a = hugeAlloc(big);
        hugeFree(a, big);
        void* b = hugeAlloc(small);
        CHECK(hugeRecycledBytes() == before);
        hugeFree(b, small);
    }
    SECTION("inside, the smallest kept block that holds the request serves it, its written pages kept") {
        HugeRecycling scope;
        const size_t before = hugeRecycledBytes();
        auto* a = static_cast<unsigned char*>(hugeAlloc(big));
        auto* c = static_cast<unsigned char*>(hugeAlloc(small));
        std::memset(a, 0xAB, big);
        hugeFree(a, big);
        hugeFree(c, small);
        auto* b = static_cast<unsigned char*>(hugeAlloc(mid));  // c (4 MiB) is too small: a serves it
        CHECK(b == a);
        CHECK(reinterpret_cast<uintptr_t>(b) % kHugePageBytes == 0);
        CHECK(b[0] == 0xAB);  // recycled, not zeroed: callers write what they make
        CHECK(hugeRecycledBytes() - before == hugeAllocSize(mid));
        auto* d = static_cast<unsigned char*>(hugeAlloc(small));  // c still kept
        CHECK(d == c);
        hugeFree(b, mid);
        hugeFree(d, small);
        // A request no kept block holds: fresh memory (the kept blocks are freed first).
        const size_t recycled = hugeRecycledBytes();
        void* e = hugeAlloc(2 * big);
        CHECK(hugeRecycledBytes() == recycled);
        hugeFree(e, 2 * big);
    }
}

TEST_CASE("huge pages: a HostArray made after another was freed reuses its block in a scope", "[huge_pages]") {
    HugeRecycling scope;
    const void* first;
    {
        HostArray<float> a(size_t(4) << 20, 1.0f);
        first = a.data();
    }
    HostArray<int> b;
    b.resize(size_t(2) << 20);  // smaller: fits the kept block
    CHECK(static_cast<const void*>(b.data()) == first);
    CHECK(inHugePages(b));
}
