// test_preview.cpp — `clrt render --preview` and `--display-server` (src/preview/): the token (403),
// no path served outside the page and its endpoints, malformed requests and oversized headers (4xx,
// the server keeps answering), a port in use (exit 1 through the binary, before any work), tev's
// protocol against a listener here that decodes its packets, and a bounded load test (50 viewers
// and 1,000 malformed requests during a tiny progressive render whose image equals one rendered
// without the preview; the same render streams to a tev listener, whose last image is that image). All [preview]; a few seconds in all on PoCL.
#include <catch.hpp>

#include <arpa/inet.h>
#include <atomic>
#include <cstring>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <thread>
#include <unistd.h>

#include <httplib.h>

#include "preview/preview_server.h"
#include "preview/tev_client.h"
#include "test_helpers.h"

using namespace clrt;
using namespace clrt::test;

namespace {

// A listening TCP socket on 127.0.0.1 at a free port.
struct Listener {
    int fd = -1, port = 0;
    Listener() {
        fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
        sockaddr_in a{};
        a.sin_family = AF_INET;
        a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        REQUIRE(bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0);
        REQUIRE(listen(fd, 16) == 0);
        socklen_t len = sizeof a;
        getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
        port = ntohs(a.sin_port);
    }
    ~Listener() { close(fd); }
};

// Sends raw bytes to 127.0.0.1:port, closes the sending side (unless closeSending is false), and returns the response's status line
// ("" if the server closed the connection without one), waiting at most 3 s.
std::string rawRequest(int port, const std::string& bytes, bool closeSending = true) {
    const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(uint16_t(port));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    std::string got;
    if (connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0) {
        send(fd, bytes.data(), bytes.size(), MSG_NOSIGNAL);
        if (closeSending) shutdown(fd, SHUT_WR);  // nothing more comes: an incomplete request ends here, not at a timeout
        pollfd p{fd, POLLIN, 0};
        char buf[512];
        while (got.find("\r\n") == std::string::npos && poll(&p, 1, 3000) == 1) {
            const ssize_t n = recv(fd, buf, sizeof buf, 0);
            if (n <= 0) break;
            got.append(buf, size_t(n));
        }
    }
    close(fd);
    return got.substr(0, got.find("\r\n"));
}

int statusCode(const std::string& statusLine) {
    return statusLine.size() >= 12 && statusLine.compare(0, 5, "HTTP/") == 0 ? std::atoi(statusLine.c_str() + 9) : 0;
}

// A preview of one 4x2 camera with an image, served on a free loopback port.
struct ServedPreview {
    PreviewState state;
    std::atomic<int> stops{0};
    PreviewServer server{state, [this] { ++stops; }, "00112233445566778899aabbccddeeff"};
    ServedPreview() {
        CameraView c;
        c.id = 7;
        c.imageName = "x.exr";
        c.width = 4;
        c.height = 2;
        CameraView big = c;  // camera 1: an EXR of 12 MB (noise), more than loopback's socket buffers hold
        big.width = big.height = 1000;
        state.setCameras({c, big});
        ImageRGB img;
        img.width = 4;
        img.height = 2;
        img.pixels.assign(24, 0.5f);
        state.publishImage(0, PassFigures{}, std::make_shared<const ImageRGB>(img));
        img.width = img.height = 1000;
        img.pixels.resize(1000 * 1000 * 3);
        uint32_t x = 12345;
        for (float& v : img.pixels) {
            x ^= x << 13, x ^= x >> 17, x ^= x << 5;
            v = float(x) * 0x1p-24f;
        }
        state.publishImage(1, PassFigures{}, std::make_shared<const ImageRGB>(img));
        server.start(parsePreviewAddress("--preview", "127.0.0.1:0"));
    }
    std::string path(const std::string& p) const { return "/" + server.token() + "/" + p; }
};

}  // namespace

TEST_CASE("preview state: the rate limit keeps the preview's own time within its budget", "[preview]") {
    PreviewState st(0.25);
    CameraView c;
    c.width = c.height = 2;
    st.setCameras({c});
    auto img = std::make_shared<const ImageRGB>();
    CHECK(st.imageInterval() == 0.25);  // nothing published yet
    CHECK(st.imageDue(0));
    st.publishImage(0, PassFigures{}, img);
    CHECK_FALSE(st.imageDue(0));        // just published: wait minInterval
    st.addServerSeconds(0.001);         // a cheap image: the minimum interval holds
    CHECK(st.imageInterval() == 0.25);
    st.addServerSeconds(0.029);         // 30 ms per image in all: 30 ms / 2% = 1.5 s between images
    st.addRenderThreadSeconds(0.0);
    CHECK(st.imageInterval() == Approx(0.030 / PreviewState::kTimeBudget));
    st.publishImage(0, PassFigures{}, img);  // two images, 30 ms for both: back to 0.75 s each
    CHECK(st.imageInterval() == Approx(0.015 / PreviewState::kTimeBudget));
    st.addRenderThreadSeconds(0.01);    // the render thread's share counts too
    CHECK(st.imageInterval() == Approx(0.020 / PreviewState::kTimeBudget));
}

TEST_CASE("threadCpuSeconds counts this thread's work, not its sleep", "[preview]") {
    const double t0 = threadCpuSeconds();
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    const double slept = threadCpuSeconds() - t0;
    CHECK(slept >= 0);
    CHECK(slept < 0.1);
    volatile double x = 0;
    const double t1 = threadCpuSeconds();
    while (threadCpuSeconds() - t1 < 0.02) x = x + 1;  // busy: its CPU time grows (ends, however slow)
    CHECK(threadCpuSeconds() - t1 >= 0.02);
}

TEST_CASE("preview server: token, paths, malformed and oversized requests", "[preview]") {
    ServedPreview sp;
    httplib::Client cli("127.0.0.1", sp.server.port());
    auto get = [&](const std::string& p) {
        auto r = cli.Get(p.c_str());
        return r ? r->status : -1;
    };
    CHECK(get(sp.path("")) == 200);
    CHECK(get(sp.path("page.js")) == 200);
    CHECK(get(sp.path("status.json")) == 200);
    CHECK(get(sp.path("image.png?cam=0")) == 200);
    CHECK(get(sp.path("image.png?cam=0&tmo=aces&ev=1.5&thumb=1")) == 200);
    CHECK(get(sp.path("image.exr?cam=0")) == 200);
    SECTION("without the token, or with a wrong one: 403") {
        CHECK(get("/") == 403);
        CHECK(get("/status.json") == 403);
        CHECK(get("/00112233445566778899aabbccddeefe/status.json") == 403);
        CHECK(get("/" + sp.server.token() + "0/status.json") == 403);  // a longer token
        CHECK(get("/" + sp.server.token().substr(0, 31) + "/") == 403);
        auto r = cli.Post("/wrong/stop", "", "text/plain");
        CHECK((r && r->status == 403));
        CHECK(sp.stops == 0);
    }
    SECTION("no file system path: traversal and unknown paths 404 (or 403 outside the token)") {
        CHECK(get(sp.path("../../../../etc/passwd")) == 404);
        CHECK(get(sp.path("%2e%2e/%2e%2e/etc/passwd")) == 404);
        CHECK(get(sp.path("page.html")) == 404);
        CHECK(get(sp.path("preview_server.cpp")) == 404);
        CHECK(get("/../" + sp.server.token() + "/../etc/passwd") != 200);
        CHECK(get(sp.path("image.png?cam=2")) == 404);  // no such camera
        CHECK(get(sp.path("image.png?cam=abc")) == 400);
        CHECK(get(sp.path("image.png?cam=0&tmo=../x")) == 400);
        CHECK(get(sp.path("image.png?cam=0&ev=nan")) == 400);
        CHECK(get(sp.path("reference.png?cam=0")) == 404);  // the camera has none
    }
    SECTION("malformed request lines, oversized headers and bodies: 4xx or a closed connection") {
        const int port = sp.server.port();
        for (const std::string& bad : std::vector<std::string>{"GARBAGE\r\n\r\n", "GET\r\n\r\n", "\r\n\r\n", std::string(9000, 'A') + "\r\n\r\n",
                                      "GET /" + sp.server.token() + "/ HTTP/1.1\r\nHost: x\r\nX: " +
                                          std::string(20000, 'h') + "\r\n\r\n",
                                      "GET /\x01\x02 HTTP/1.1\r\n\r\n"}) {
            const int code = statusCode(rawRequest(port, bad));
            INFO(bad.substr(0, 40));
            CHECK((code == 0 || (code >= 400 && code < 500)));
        }
        const int post = statusCode(rawRequest(port, "POST " + sp.path("stop") + " HTTP/1.1\r\nHost: x\r\nContent-Length: 4096\r\n\r\n" +
                                                         std::string(4096, 'b'), false));
        CHECK((post == 413 || post == 0));  // 0: the server's reset (it closes with our body unread) beat its 413
        CHECK(sp.stops == 0);
        CHECK(get(sp.path("status.json")) == 200);  // still serving
        auto r = cli.Post(sp.path("stop").c_str(), "", "text/plain");
        CHECK((r && r->status == 200));
        CHECK(sp.stops == 1);
    }
}

// (cpp-httplib ignores SIGPIPE process-wide when it listens, so this checks that the server goes on
// after write errors, not the SIGPIPE blocking of preview_server.cpp.)
TEST_CASE("preview server: viewers that go away mid-answer; the server goes on", "[preview]") {
    ServedPreview sp;
    const std::string request = "GET " + sp.path("image.exr?cam=1") + " HTTP/1.1\r\nHost: x\r\n\r\n";
    for (int i = 0; i < 2; ++i) {
        const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
        sockaddr_in a{};
        a.sin_family = AF_INET;
        a.sin_port = htons(uint16_t(sp.server.port()));
        a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
        REQUIRE(connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0);
        send(fd, request.data(), request.size(), MSG_NOSIGNAL);
        pollfd p{fd, POLLIN, 0};
        poll(&p, 1, 5000);  // the answer has begun
        close(fd);          // unread data: a reset; the server's next write fails
    }
    httplib::Client cli("127.0.0.1", sp.server.port());
    auto r = cli.Get(sp.path("image.exr?cam=1").c_str());  // the process is alive and still serving
    REQUIRE(r);
    CHECK(r->status == 200);
    CHECK(r->body.size() > 8000000);
}

TEST_CASE("preview: address parsing, a port in use exits 1 before any work", "[preview]") {
    CHECK(parsePreviewAddress("--preview", "8080").host == "127.0.0.1");
    CHECK(parsePreviewAddress("--preview", "8080").loopback);
    CHECK_FALSE(parsePreviewAddress("--preview", "0.0.0.0:8080").loopback);
    CHECK(parsePreviewAddress("--preview", "[::1]:9").host == "::1");
    CHECK_THROWS(parsePreviewAddress("--preview", "80x"));
    CHECK_THROWS(parsePreviewAddress("--preview", "70000"));
    CHECK(randomToken().size() == 32);
    CHECK(randomToken() != randomToken());
    Listener taken;
    TempDir d;
    const int rc = runClrt("render " + d.file("no_such_scene.xml") + " --preview 127.0.0.1:" + std::to_string(taken.port),
                           d.file("log"));
    const std::string log = readFileBytes(d.file("log"));
    INFO(log);
    CHECK(rc == 1);
    CHECK(log.find("--preview: cannot listen on 127.0.0.1:" + std::to_string(taken.port)) != std::string::npos);
    CHECK(std::count(log.begin(), log.end(), '\n') == 1);
}

namespace {

// tev's packets as a listener receives them: (type, payload after the type byte).
std::vector<std::pair<int, std::string>> decodeTevStream(const std::string& bytes) {
    std::vector<std::pair<int, std::string>> out;
    size_t at = 0;
    while (at + 5 <= bytes.size()) {
        uint32_t len = 0;
        std::memcpy(&len, bytes.data() + at, 4);
        REQUIRE(len >= 5);
        REQUIRE(at + len <= bytes.size());
        out.emplace_back(int(uint8_t(bytes[at + 4])), bytes.substr(at + 5, len - 5));
        at += len;
    }
    CHECK(at == bytes.size());
    return out;
}

struct Reader {  // reads tev's fields in order
    const std::string& s;
    size_t at = 0;
    std::string str() {
        const size_t end = s.find('\0', at);
        std::string v = s.substr(at, end - at);
        at = end + 1;
        return v;
    }
    template <class T> T num() {
        T v;
        std::memcpy(&v, s.data() + at, sizeof v);
        at += sizeof v;
        return v;
    }
};

}  // namespace

TEST_CASE("--display-server: tev's CreateImage and UpdateImage packets, decoded by a listener", "[preview]") {
    ImageRGB img;
    img.width = 130;  // two tiles across
    img.height = 3;
    for (int i = 0; i < img.width * img.height * 3; ++i) img.pixels.push_back(float(i) * 0.25f);
    Listener tev;
    std::string received;
    std::thread server([&] {
        const int c = accept(tev.fd, nullptr, nullptr);
        char buf[65536];
        ssize_t n;
        while ((n = recv(c, buf, sizeof buf, 0)) > 0) received.append(buf, size_t(n));
        close(c);
    });
    {
        TevClient client("127.0.0.1:" + std::to_string(tev.port));
        CHECK(client.connected());
        client.createImage("img.exr", img.width, img.height);
        client.updateImage("img.exr", std::make_shared<const ImageRGB>(img));
    }  // the destructor sends what is queued and closes
    server.join();
    const auto packets = decodeTevStream(received);
    REQUIRE(packets.size() == 3);
    Reader create{packets[0].second};
    CHECK(packets[0].first == 4);
    CHECK(create.num<uint8_t>() == 1);
    CHECK(create.str() == "img.exr");
    CHECK(create.num<int32_t>() == 130);
    CHECK(create.num<int32_t>() == 3);
    CHECK(create.num<int32_t>() == 3);
    CHECK(create.str() == "R");
    CHECK(create.str() == "G");
    CHECK(create.str() == "B");
    CHECK(create.at == packets[0].second.size());
    int pixelsSeen = 0;
    for (size_t p = 1; p < 3; ++p) {
        Reader u{packets[p].second};
        CHECK(packets[p].first == 6);
        CHECK(u.num<uint8_t>() == 0);
        CHECK(u.str() == "img.exr");
        REQUIRE(u.num<int32_t>() == 3);
        CHECK(u.str() == "R");
        CHECK(u.str() == "G");
        CHECK(u.str() == "B");
        const int x = u.num<int32_t>(), y = u.num<int32_t>(), w = u.num<int32_t>(), h = u.num<int32_t>();
        CHECK(y == 0);
        CHECK(h == 3);
        CHECK(x == (p == 1 ? 0 : 128));
        int64_t offsets[3], strides[3];
        for (auto& o : offsets) o = u.num<int64_t>();
        for (auto& s : strides) s = u.num<int64_t>();
        REQUIRE(u.at + size_t(w) * h * 3 * 4 == packets[p].second.size());
        const size_t data = u.at;
        for (int yy = 0; yy < h; ++yy)
            for (int xx = 0; xx < w; ++xx, ++pixelsSeen)
                for (int c = 0; c < 3; ++c) {
                    float v;
                    std::memcpy(&v, packets[p].second.data() + data + 4 * size_t((yy * w + xx) * strides[c] + offsets[c]), 4);
                    REQUIRE(v == img.at(x + xx, y + yy, c));
                }
    }
    CHECK(pixelsSeen == 130 * 3);
    SECTION("tev not running: one warning, not connected") {
        int port;
        {
            Listener gone;
            port = gone.port;
        }  // closed: nothing listens there now
        TevClient none("127.0.0.1:" + std::to_string(port));
        CHECK_FALSE(none.connected());
        none.updateImage("x", std::make_shared<const ImageRGB>(img));  // ignored
    }
}

TEST_CASE("preview under load: 50 viewers and 1,000 malformed requests during a render; same image", "[preview][cli]") {
    TempDir d;
    std::filesystem::create_directories(d.path / "a");
    std::filesystem::create_directories(d.path / "b");
    const std::string base = "render " + std::string(CLRT_SOURCE_DIR) + "/scenes/preview_box.xml --camera 1 " +
                             "--resolution 8x6 --spp 128 --target-error 1e-12 --seed 5" + deviceArg();  // 4 passes
    REQUIRE(runClrt(base + " -o " + d.file("a"), d.file("loga")) == 0);
    Listener tev;  // --display-server on the same render: tev's packets, decoded below
    std::string tevBytes;
    std::thread tevThread([&] {
        const int c = accept(tev.fd, nullptr, nullptr);
        char buf[65536];
        ssize_t n;
        while ((n = recv(c, buf, sizeof buf, 0)) > 0) tevBytes.append(buf, size_t(n));
        close(c);
    });
    std::atomic<int> rc{-2};
    std::thread render([&] {
        rc = runClrt(base + " -o " + d.file("b") + " --preview 127.0.0.1:0 --preview-keep --display-server 127.0.0.1:" +
                         std::to_string(tev.port),
                     d.file("logb"));
    });
    std::string url;
    for (int i = 0; i < 600 && url.empty(); ++i) {  // the URL line, at most 30 s
        const std::string log = readFileBytes(d.file("logb"));
        const size_t at = log.find("preview: http://127.0.0.1:");
        if (at != std::string::npos && log.find('\n', at) != std::string::npos)
            url = log.substr(at + 9, log.find('\n', at) - at - 9);
        else
            std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    REQUIRE(!url.empty());
    const int port = std::atoi(url.c_str() + 17);
    const std::string prefix = url.substr(url.find('/', 7));  // /TOKEN/
    std::atomic<bool> finished{false}, stopViewers{false}, rendering{false};
    std::atomic<int> viewed{0}, images{0}, malformedAnswered{0};
    std::vector<std::thread> threads;
    for (int v = 0; v < 50; ++v)
        threads.emplace_back([&] {
            httplib::Client cli("127.0.0.1", port);
            cli.set_read_timeout(10, 0);
            while (!stopViewers) {
                auto s = cli.Get((prefix + "status.json").c_str());
                if (s && s->status == 200) {
                    ++viewed;
                    if (s->body.find("\"finished\":true") != std::string::npos) finished = true;
                    if (s->body.find("\"phase\":\"rendering\"") != std::string::npos) rendering = true;
                    if (s->body.find("\"hasImage\":true") != std::string::npos) {
                        auto im = cli.Get((prefix + "image.png?cam=0").c_str());
                        if (im && im->status == 200) ++images;
                    }
                }
                std::this_thread::sleep_for(std::chrono::milliseconds(20));
            }
        });
    const std::string bad[] = {"GARBAGE\r\n\r\n", "GET " + prefix + " HTTP/1.1\r\nX: " + std::string(10000, 'x') + "\r\n\r\n",
                               "GET /" + std::string(9000, 'p') + " HTTP/1.1\r\n\r\n", "GET " + prefix + "status.json HTTP/1.1\r\nHost",
                               "POST " + prefix + "stop HTTP/1.1\r\nContent-Length: 999999\r\n\r\nxx"};
    std::vector<std::thread> flood;
    for (int t = 0; t < 4; ++t)
        flood.emplace_back([&, t] {
            for (int i = 0; i < 600 && !rendering && !finished; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
            for (int i = 0; i < 250; ++i)
                if (statusCode(rawRequest(port, bad[size_t(t * 250 + i) % 5])) != 200) ++malformedAnswered;
        });
    for (auto& t : flood) t.join();
    for (int i = 0; i < 1200 && !finished; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(50));
    stopViewers = true;
    for (auto& t : threads) t.join();
    httplib::Client cli("127.0.0.1", port);
    auto stop = cli.Post((prefix + "stop").c_str(), "", "text/plain");  // ends --preview-keep, as Ctrl-C
    CHECK((stop && stop->status == 200));
    render.join();
    tevThread.join();
    const std::string log = readFileBytes(d.file("logb"));
    INFO(log);
    CHECK(finished);
    CHECK(malformedAnswered == 1000);
    CHECK(viewed > 50);
    CHECK(images > 0);
    CHECK(rc == 130);  // --preview-keep ends with Ctrl-C (here the page's Stop)
    const ImageRGB a = readImage(d.file("a/preview_box.exr")), b = readImage(d.file("b/preview_box.exr"));
    REQUIRE(a.pixels.size() == b.pixels.size());
    CHECK(std::memcmp(a.pixels.data(), b.pixels.data(), a.pixels.size() * sizeof(float)) == 0);
    // tev got CreateImage, then updates; the last one is the image written.
    const auto packets = decodeTevStream(tevBytes);
    REQUIRE(packets.size() >= 2);
    CHECK(packets.front().first == 4);
    Reader last{packets.back().second};
    CHECK(packets.back().first == 6);
    last.num<uint8_t>();
    CHECK(last.str() == "preview_box.exr");
    REQUIRE(last.num<int32_t>() == 3);
    last.str(), last.str(), last.str();
    last.at += 4 * 4 + 6 * 8;  // x, y, width, height; offsets, strides (checked in the protocol test)
    REQUIRE(last.at + a.pixels.size() * 4 == packets.back().second.size());
    CHECK(std::memcmp(packets.back().second.data() + last.at, a.pixels.data(), a.pixels.size() * 4) == 0);
}
