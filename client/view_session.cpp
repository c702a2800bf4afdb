#include "view_session.h"

#include <fmt/format.h>
#include <openssl/crypto.h>

#include <chrono>
#include <optional>

#include "connection.h"
#include "film/film.h"
#include "remote_common.h"
#include "tile_canvas.h"
#include "view_messages.h"

namespace omega::client {

namespace proto = omega::protocol;

namespace {

struct Closed {};  // the WebSocket is gone or must close: unwinds the relay

bool same_secret(const std::string& a, const std::string& b) {
    return a.size() == b.size() && CRYPTO_memcmp(a.data(), b.data(), a.size()) == 0;
}

// The relay proper. Lives on the session thread only, so nothing here needs a lock.
class Relay {
public:
    using Next = std::function<std::optional<std::string>(std::chrono::milliseconds)>;
    Relay(const ViewSessionConfig& cfg, const ViewSession::SendFn& send, Next next)
        : cfg_(cfg), send_(send), next_(std::move(next)) {}

    void run() {
        auto first = next_(std::chrono::milliseconds(60000));
        if (!first) return;
        auto cmd = decode_view_command(*first);
        if (!cmd) return text(view_error(0, "bad_request", cmd.message()));
        if (cmd->kind != ViewCommandKind::login) return text(view_error(cmd->id, "auth_required", "log in first"));
        if (!login(*cmd)) return;
        send_list(0);
        auto next_list = Clock::now();
        for (;;) {
            // The page's requests, then the stream of the open job (or a short wait for the page).
            std::optional<std::string> in;
            if (sub_id_) {
                if (auto f = stream_->try_read(Clock::now() + std::chrono::milliseconds(40))) on_stream(*f);
                in = next_(std::chrono::milliseconds(0));
            } else {
                in = next_(std::chrono::milliseconds(40));
            }
            for (; in; in = next_(std::chrono::milliseconds(0))) on_command(*in, next_list);
            if (Clock::now() >= next_list) {
                send_list(0);
                next_list = Clock::now() + std::chrono::milliseconds(long(cfg_.list_interval_s * 1000));
            }
        }
    }

    void text(const std::string& s) {
        if (!send_(s, false)) throw Closed{};
    }
    void binary(const std::string& s) {
        if (!send_(s, true)) throw Closed{};
    }

private:
    bool login(const ViewCommand& c) {
        if (c.token.empty()) {
            text(view_error(c.id, "auth_failed", "a token is required"));
            return false;
        }
        // A Unix socket authenticates this process, not the page: the access key stands in.
        if (cfg_.daemon.kind == Address::Kind::unix_socket && !same_secret(c.token, cfg_.access_key)) {
            text(view_error(c.id, "auth_failed", "wrong access key (omega view printed it at start)"));
            return false;
        }
        ConnectOptions o;
        o.client_name = "omega-view/0.1";
        o.user = c.user.empty() ? std::string("-") : c.user;  // never the bridge's own $OMEGA_USER
        o.token = c.token;                                    // non-empty: never $OMEGA_TOKEN
        try {
            ctrl_.emplace(Connection::open(cfg_.daemon, o));
            const auto& w = ctrl_->welcome();
            if (w.auth != proto::AuthMethod::hmac_sha256 && !same_secret(c.token, cfg_.access_key)) {
                text(view_error(c.id, "auth_failed", "wrong access key (omega view printed it at start)"));
                return false;
            }
            stream_.emplace(Connection::open(cfg_.daemon, o));
            user_ = w.auth == proto::AuthMethod::hmac_sha256 ? c.user : w.user.value_or("tcp");
            text(view_welcome(c.id, user_, w.server, proto::to_string(w.auth)));
            return true;
        } catch (const ClientError& e) {
            const std::string m = e.what();
            text(view_error(c.id, m.find("auth_failed") != std::string::npos ? "auth_failed" : "unreachable", m));
            return false;
        }
    }

    // An `error` frame as the page's error reply; true when r was one.
    bool relay_error(uint64_t page_id, const proto::DecodedFrame& r) {
        if (r.type != proto::MessageType::error) return false;
        auto e = proto::decode<proto::Error>(r);
        text(view_error(page_id, e ? proto::to_string(e->code) : "internal", e ? e->message : e.message()));
        return true;
    }

    void send_list(uint64_t page_id) {
        proto::List l{ctrl_->next_id()};
        auto r = ctrl_->request(proto::encode(l), l.id);
        if (relay_error(page_id, r)) return;
        text(view_jobs(page_id, user_, ctrl_->expect<proto::JobList>(r).jobs));
    }

    template <class Req>
    void simple(const ViewCommand& c, Req req) {
        req.id = ctrl_->next_id();
        auto r = ctrl_->request(proto::encode(req), req.id);
        if (!relay_error(c.id, r)) text(view_ok(c.id, c.kind, c.job));
    }

    void on_command(const std::string& raw, Clock::time_point& next_list) {
        auto d = decode_view_command(raw);
        if (!d) return text(view_error(0, "bad_request", d.message()));
        const ViewCommand& c = *d;
        switch (c.kind) {
            case ViewCommandKind::login: return text(view_error(c.id, "bad_request", "already logged in"));
            case ViewCommandKind::list: return send_list(c.id);
            case ViewCommandKind::open: return open(c);
            case ViewCommandKind::close: unsubscribe(); return text(view_ok(c.id, c.kind, 0));
            case ViewCommandKind::cancel: simple(c, proto::Cancel{0, c.job}); break;
            case ViewCommandKind::pause: simple(c, proto::Pause{0, c.job}); break;
            case ViewCommandKind::resume: simple(c, proto::Resume{0, c.job}); break;
            case ViewCommandKind::set_priority: simple(c, proto::SetPriority{0, c.job, c.priority}); break;
            case ViewCommandKind::fetch: {
                proto::Fetch f{ctrl_->next_id(), c.job};
                auto r = ctrl_->request(proto::encode(f), f.id);
                if (!relay_error(c.id, r)) binary(pack_exr(c.job, ctrl_->expect<proto::Image>(r).exr));
                return;
            }
        }
        next_list = Clock::now();  // a control changed a job: show it at once
    }

    void unsubscribe() {
        if (!sub_id_) return;
        proto::Unsubscribe u{stream_->next_id(), sub_job_};
        stream_->send(proto::encode(u));  // its ok and any frame still in flight carry ids we drop
        sub_id_ = 0;
    }

    void open(const ViewCommand& c) {
        unsubscribe();
        proto::Status s{ctrl_->next_id(), c.job};
        auto r = ctrl_->request(proto::encode(s), s.id);
        if (relay_error(c.id, r)) return;
        const proto::JobInfo info = ctrl_->expect<proto::JobInfoReply>(r).info;
        text(view_job(c.id, user_, info));
        open_id_ = c.id;
        warnings_.reset();
        if (!is_terminal(info.state)) {
            sub_id_ = stream_->next_id();
            sub_job_ = c.job;
            stream_->send(proto::encode(proto::Subscribe{sub_id_, c.job}));
            return;
        }
        // An ended job streams nothing: its final image goes to the page as one tile.
        proto::Fetch f{ctrl_->next_id(), c.job};
        auto img = ctrl_->request(proto::encode(f), f.id);
        if (img.type == proto::MessageType::image) {
            const auto m = ctrl_->expect<proto::Image>(img);
            send_pixels(c.job, m.exr, m.pass, m.spp, nullptr);
        } else if (relay_error(c.id, img)) {
            return;
        }
        text(view_done(c.id, proto::Done{c.id, c.job, info.state, info.progress, std::nullopt}));
    }

    // Decodes an EXR (a tile or a whole image) and sends its floats; nullptr rect: any window.
    void send_pixels(uint64_t job, const std::string& exr, uint64_t pass, uint64_t spp, const proto::Rect* rect) {
        ExrImage img;
        try {
            img = decode_exr_memory(std::span(reinterpret_cast<const uint8_t*>(exr.data()), exr.size()));
        } catch (const std::exception& e) {
            return text(view_error(open_id_, "internal", fmt::format("job {}: an undecodable EXR: {}", job, e.what())));
        }
        if (img.width <= 0 || img.height <= 0 || img.x0 < 0 || img.y0 < 0 || img.x0 + img.width > img.display_width ||
            img.y0 + img.height > img.display_height ||
            (rect && (rect->x0 != uint32_t(img.x0) || rect->y0 != uint32_t(img.y0) ||
                      rect->x1 != uint32_t(img.x0 + img.width) || rect->y1 != uint32_t(img.y0 + img.height))))
            return text(view_error(open_id_, "internal", fmt::format("job {}: a tile's EXR does not match its rect", job)));
        FloatTile t;
        t.job = job;
        t.x0 = uint32_t(img.x0);
        t.y0 = uint32_t(img.y0);
        t.x1 = uint32_t(img.x0 + img.width);
        t.y1 = uint32_t(img.y0 + img.height);
        t.film_width = uint32_t(img.display_width);
        t.film_height = uint32_t(img.display_height);
        t.pass = uint32_t(std::min<uint64_t>(pass, UINT32_MAX));
        t.spp = uint32_t(std::min<uint64_t>(spp, UINT32_MAX));
        t.rgb = img.rgb;
        t.var = img.var;
        binary(pack_float_tile(t));
        const ExrMeta meta = meta_from_attributes(img.attributes);
        if (!warnings_ || *warnings_ != meta.warnings) {
            warnings_ = meta.warnings;
            text(view_warnings(open_id_, job, meta.warnings, meta.nonfinite));
        }
    }

    void on_stream(const proto::DecodedFrame& f) {
        if (f.id != sub_id_) return;  // a subscription the page already left
        switch (f.type) {
            case proto::MessageType::tile: {
                const auto t = stream_->expect<proto::Tile>(f);
                return send_pixels(t.job, t.exr, t.pass, t.spp, &t.rect);
            }
            case proto::MessageType::progress: {
                const auto p = stream_->expect<proto::Progress>(f);
                return text(view_progress(open_id_, p.job, p.state, p.progress));
            }
            case proto::MessageType::done:
                sub_id_ = 0;
                return text(view_done(open_id_, stream_->expect<proto::Done>(f)));
            case proto::MessageType::error: sub_id_ = 0; relay_error(open_id_, f); return;
            default: return;  // ok
        }
    }

    const ViewSessionConfig& cfg_;
    const ViewSession::SendFn& send_;
    Next next_;
    std::optional<Connection> ctrl_, stream_;
    std::string user_;
    uint64_t sub_id_ = 0, sub_job_ = 0, open_id_ = 0;
    std::optional<std::vector<std::string>> warnings_;
};

}  // namespace

ViewSession::ViewSession(ViewSessionConfig cfg, SendFn send, std::function<void()> close)
    : cfg_(std::move(cfg)), send_(std::move(send)), close_(std::move(close)) {
    thread_ = std::thread([this] { run(); });
}

ViewSession::~ViewSession() {
    stop();
    if (thread_.joinable()) thread_.join();
}

bool ViewSession::push(std::string text) {
    std::lock_guard lock(mu_);
    if (inbox_.size() >= 256) return false;
    inbox_.push_back(std::move(text));
    cv_.notify_one();
    return true;
}

void ViewSession::stop() {
    std::lock_guard lock(mu_);
    stopping_ = true;
    cv_.notify_one();
}

void ViewSession::run() {
    // Runs on the session thread. next() waits (taking mu_) for the page's next message.
    Relay relay(cfg_, send_, [this](std::chrono::milliseconds wait) -> std::optional<std::string> {
        std::unique_lock lock(mu_);
        cv_.wait_for(lock, wait, [&] { return stopping_ || !inbox_.empty(); });
        if (stopping_) throw Closed{};
        if (inbox_.empty()) return std::nullopt;
        std::string s = std::move(inbox_.front());
        inbox_.pop_front();
        return s;
    });
    try {
        relay.run();
    } catch (const Closed&) {
        return;  // the page left: nothing to tell it
    } catch (const ClientError& e) {
        try {
            relay.text(view_error(0, "unreachable", e.what()));
        } catch (...) {
        }
    } catch (const std::exception& e) {
        try {
            relay.text(view_error(0, "internal", e.what()));
        } catch (...) {
        }
    }
    close_();
}

}  // namespace omega::client
