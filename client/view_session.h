#pragma once
// One WebSocket of the job page: a thread that owns two protocol sessions with omegad (one for
// requests, one for the tile stream of the job the page has open) and relays between them and the
// page. The page's messages arrive on a civetweb worker thread (push); everything else runs on the
// session's own thread.
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "address.h"

namespace omega::client {

struct ViewSessionConfig {
    Address daemon;
    // Checked instead of the daemon's HMAC when the daemon does not authenticate users itself
    // (a Unix socket, or loopback TCP without tcp_users): the page must send it as its token.
    std::string access_key;
    double list_interval_s = 1.0;
};

class ViewSession {
public:
    // send(text, binary) writes one WebSocket message; it returns false once the socket is gone.
    // It is called on the session thread only. close() asks civetweb to close the WebSocket.
    using SendFn = std::function<bool(const std::string& data, bool binary)>;
    ViewSession(ViewSessionConfig cfg, SendFn send, std::function<void()> close);
    // Joins the session thread. Called on the civetweb worker of this WebSocket (close handler).
    ~ViewSession();
    ViewSession(const ViewSession&) = delete;
    ViewSession& operator=(const ViewSession&) = delete;

    // A text message from the page. Called on this WebSocket's civetweb worker thread; takes mu_.
    // Returns false when the page floods (over 256 messages unread): the caller closes.
    bool push(std::string text);
    // The WebSocket is gone: the thread stops at its next wait. Any thread; takes mu_.
    void stop();

private:
    void run();  // the session thread

    ViewSessionConfig cfg_;
    SendFn send_;
    std::function<void()> close_;
    std::mutex mu_;  // guards inbox_ and stopping_
    std::condition_variable cv_;
    std::deque<std::string> inbox_;
    bool stopping_ = false;
    std::thread thread_;
};

}  // namespace omega::client
