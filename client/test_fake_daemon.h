#pragma once
// For the client's tests: a tiny omegad stand-in. It listens on a Unix socket in a fresh temp
// folder, answers hello with welcome (auth peer), and hands every later frame to a scripted
// handler, one thread per connection. Speaks the protocol library, like the real daemon.
#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <poll.h>
#include <unistd.h>

#include <atomic>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "connection.h"
#include "protocol/messages.h"

namespace omega::client::test {

namespace fs = std::filesystem;

struct TempDir {
    fs::path path;
    TempDir() {
        std::random_device rd;
        path = fs::temp_directory_path() / ("omega_client_" + std::to_string(rd() % 100000000));
        fs::create_directories(path);
    }
    ~TempDir() {
        std::error_code ec;
        fs::remove_all(path, ec);
    }
    fs::path write(const std::string& name, const std::string& text) const {
        auto p = path / name;
        fs::create_directories(p.parent_path());
        std::ofstream(p, std::ios::binary) << text;
        return p;
    }
};

inline std::string slurp(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

class FakeDaemon {
public:
    struct Session {
        FrameSocket* sock;
        int index;  // connection number, from 0
        void send(const protocol::Frame& f) { sock->send(f); }
        template <class M>
        void reply(const M& m) {
            send(protocol::encode(m));
        }
    };
    using Handler = std::function<void(Session&, const protocol::DecodedFrame&)>;

    explicit FakeDaemon(Handler h, bool refuse_hello = false) : handler_(std::move(h)), refuse_hello_(refuse_hello) {
        path_ = (dir_.path / "d.sock").string();
        listen_fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
        sockaddr_un sa{};
        sa.sun_family = AF_UNIX;
        std::strncpy(sa.sun_path, path_.c_str(), sizeof sa.sun_path - 1);
        if (::bind(listen_fd_, reinterpret_cast<sockaddr*>(&sa), sizeof sa) != 0 || ::listen(listen_fd_, 64) != 0)
            throw std::runtime_error("fake daemon: cannot listen on " + path_);
        accept_thread_ = std::thread([this] { accept_loop(); });
    }
    ~FakeDaemon() {
        stop_ = true;
        accept_thread_.join();
        std::lock_guard lock(mu_);
        for (auto& t : threads_) t.join();
        ::close(listen_fd_);
    }
    std::string address() const { return "unix:" + path_; }
    int connections() const { return next_index_; }

private:
    void accept_loop() {
        while (!stop_) {
            pollfd p{listen_fd_, POLLIN, 0};
            if (::poll(&p, 1, 20) <= 0) continue;
            const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_CLOEXEC);
            if (fd < 0) continue;
            std::lock_guard lock(mu_);
            threads_.emplace_back([this, fd, index = next_index_++] { serve(fd, index); });
        }
    }
    void serve(int fd, int index) {
        FrameSocket sock(fd);
        Session s{&sock, index};
        bool greeted = false;
        try {
            while (!stop_) {
                protocol::DecodedFrame f;
                const auto st = sock.read(Clock::now() + std::chrono::milliseconds(20), f);
                if (st == FrameSocket::ReadStatus::timeout) continue;
                if (st != FrameSocket::ReadStatus::frame) return;
                if (f.type == protocol::MessageType::bye) return;
                if (!greeted) {
                    if (f.type != protocol::MessageType::hello) return;
                    if (refuse_hello_) {
                        s.reply(protocol::Error{f.id, protocol::ErrorCode::unsupported_version,
                                                "this daemon speaks protocol versions 7..9"});
                        return;
                    }
                    protocol::Welcome w;
                    w.id = f.id;
                    w.server = "fake-omegad/0";
                    w.auth = protocol::AuthMethod::peer;
                    w.user = "1000";
                    s.reply(w);
                    greeted = true;
                    continue;
                }
                handler_(s, f);
            }
        } catch (const std::exception&) {
            // the client went away mid-reply
        }
    }

    TempDir dir_;
    std::string path_;
    int listen_fd_ = -1;
    Handler handler_;
    bool refuse_hello_ = false;
    std::atomic<bool> stop_{false};
    std::atomic<int> next_index_{0};
    std::thread accept_thread_;
    std::mutex mu_;
    std::vector<std::thread> threads_;
};

}  // namespace omega::client::test
