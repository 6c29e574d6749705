// The node's resource manager (resources.hpp).
#include "tetiso/resources.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "tetiso/error.hpp"

namespace tetiso {

void PerformanceModel::add(double size, double seconds) {
    size = std::max(size, 1.0);
    seconds = std::max(seconds, 1e-9);
    History& h = by_size_[size];
    ++h.count;
    h.sum += seconds;
    ++samples_;
    total_ += seconds;
    total_size_ += size;
    const double x = std::log(size), y = std::log(seconds);
    sx_ += x;
    sy_ += y;
    sxx_ += x * x;
    sxy_ += x * y;
}

std::optional<double> PerformanceModel::predict(double size) const {
    size = std::max(size, 1.0);
    if (const auto it = by_size_.find(size); it != by_size_.end() && it->second.count >= kMinSamples)
        return it->second.sum / it->second.count;
    if (samples_ < kMinSamples) return std::nullopt;
    const double n = samples_;
    const double spread = n * sxx_ - sx_ * sx_;
    // One size only (or sizes too close to tell apart): in proportion to
    // size, as a batch counts as its tasks one after another (a GPU that has
    // only run batches of 8 takes one task in an eighth of the time).
    if (by_size_.size() < 2 || spread <= 1e-12 * n * n) return *rate() * size;
    const double b = (n * sxy_ - sx_ * sy_) / spread;
    const double log_a = (sy_ - b * sx_) / n;
    return std::exp(log_a + b * std::log(size));
}

ResourceManager::ResourceManager(std::vector<ManagedDevice> devices)
    : devices_(std::move(devices)),
      transfer_seconds_(devices_.size(), 0.0),
      transfer_size_(devices_.size(), 0.0) {
    if (devices_.empty()) throw Error("a resource manager needs at least one device");
    for (const ManagedDevice& d : devices_)
        if (!(d.capacity > 0)) throw Error("device " + d.name + " has no capacity");
}

const PerformanceModel* ResourceManager::model(int kind, int device) const {
    const auto it = models_.find({kind, device});
    return it == models_.end() ? nullptr : &it->second;
}

std::optional<double> ResourceManager::estimate(int kind, double size, int device) const {
    if (const PerformanceModel* m = model(kind, device)) {
        if (const auto seconds = m->predict(size)) return seconds;
        // Too few to trust, but measured here: nearer the truth than any
        // guess (a GPU's first task can be fifty times faster than the CPU's
        // prior).
        if (const auto rate = m->rate()) return *rate * std::max(size, 1.0);
    }
    if (const auto it = priors_.find({kind, device}); it != priors_.end()) return it->second * std::max(size, 1.0);
    return std::nullopt;
}

void ResourceManager::set_prior(int kind, int device, double seconds_per_size) {
    if (!(seconds_per_size > 0) || !std::isfinite(seconds_per_size))
        throw Error("a prior of " + std::to_string(seconds_per_size) + " s per unit of size is not a time");
    priors_[{kind, device}] = seconds_per_size;
}

double ResourceManager::predict(int kind, double size, int device) const {
    const auto d = static_cast<std::size_t>(device);
    const double transfer =
        (transfer_size_[d] > 0 ? transfer_seconds_[d] / transfer_size_[d] : devices_[d].transfer_per_size) * size;
    if (const auto seconds = estimate(kind, size, device)) return *seconds + transfer;
    // Nothing known here: somewhat faster than the fastest device that knows
    // the task, so that this one is tried and learns, but is not flooded
    // meanwhile with tasks each thought to take nothing.
    std::optional<double> fastest;
    for (std::size_t other = 0; other < devices_.size(); ++other)
        if (const auto seconds = estimate(kind, size, static_cast<int>(other)))
            fastest = std::min(fastest.value_or(*seconds), *seconds);
    return (fastest ? *fastest / kUncalibratedSpeedup : kUncalibratedSeconds) + transfer;
}

double ResourceManager::expected_seconds(const ResourceRequest& request, int device, double now) const {
    const double seconds = predict(request.kind, request.size, device);
    if (const PerformanceModel* m = model(request.kind, device); m && m->predict(request.size)) return seconds;
    // Uncalibrated here, but a task of the same kind that has run here for
    // s seconds and not ended says such tasks take at least s: without this
    // floor a device whose first tasks are still running looks faster than
    // one that has finished some (its guess is derived from theirs), and
    // is handed every task in the meantime.
    double running = 0;
    for (const auto& [ticket, b] : bookings_)
        if (b.device == device && b.started && b.request.kind == request.kind) running = std::max(running, now - b.start);
    return std::max(seconds, running);
}

double ResourceManager::units_booked_at(int device, double time, double now) const {
    double units = 0;
    for (const auto& [ticket, b] : bookings_) {
        if (b.device != device) continue;
        // A started task that overran its prediction still holds its units;
        // one not started yet cannot have started before now.
        const double start = b.started ? b.start : std::max(b.start, now);
        const double end = b.started ? std::max(b.end, now + 1e-9) : start + (b.end - b.start);
        if (start <= time && time < end) units += b.units;
    }
    return units;
}

double ResourceManager::admission_time(int device, double units, double seconds, double now) const {
    const double capacity = devices_[static_cast<std::size_t>(device)].capacity;
    // Grants are served in order: none starts before one booked earlier on
    // the device that has not started. (Its booked start, not a start
    // remembered at booking: a device that ends its work early starts the
    // grants queued behind it early, and a new one may follow them at once.)
    double earliest = now;
    for (const auto& [ticket, b] : bookings_)
        if (b.device == device && !b.started) earliest = std::max(earliest, b.start);
    // The units in use change only where a booking starts or ends: the
    // request fits from t if it fits at t and at every start within its span.
    std::vector<double> candidates{earliest}, starts;
    for (const auto& [ticket, b] : bookings_) {
        if (b.device != device) continue;
        const double start = b.started ? b.start : std::max(b.start, now);
        const double end = b.started ? std::max(b.end, now + 1e-9) : start + (b.end - b.start);
        if (end > earliest) candidates.push_back(end);
        starts.push_back(start);
    }
    std::sort(candidates.begin(), candidates.end());
    for (const double t : candidates) {
        bool fits = units_booked_at(device, t, now) + units <= capacity;
        for (const double s : starts)
            if (fits && s > t && s < t + seconds) fits = units_booked_at(device, s, now) + units <= capacity;
        if (fits) return t;
    }
    return candidates.back(); // after every booking the device is empty, and units <= capacity
}

Grant ResourceManager::candidate(const ResourceRequest& request, int device, int count, double now) const {
    ResourceRequest whole = request;
    whole.size = request.size * count;
    Grant g;
    g.device = device;
    g.count = count;
    const PerformanceModel* m = model(request.kind, device);
    const bool fitted = m && m->sizes() >= 2 && m->predict(whole.size);
    g.predicted_seconds = count == 1 || fitted ? expected_seconds(whole, device, now)
                                               : count * expected_seconds(request, device, now);
    g.start = admission_time(device, request.units[static_cast<std::size_t>(device)], g.predicted_seconds, now);
    return g;
}

Grant ResourceManager::request(const ResourceRequest& request, double now) {
    const auto most = [&](std::size_t d) { return d < request.batch.size() ? std::max(1, request.batch[d]) : 1; };
    Grant best;
    double best_end = std::numeric_limits<double>::infinity();
    // Where the task alone would end first, and where on a device that takes
    // one task at a time.
    double alone_end = std::numeric_limits<double>::infinity();
    Grant alone;
    for (std::size_t d = 0; d < devices_.size(); ++d) {
        const double units = d < request.units.size() ? request.units[d] : 0;
        if (!(units > 0) || units > devices_[d].capacity) continue;
        const Grant g = candidate(request, static_cast<int>(d), 1, now);
        const double end = g.start + g.predicted_seconds;
        if (most(d) == 1 && end < alone_end) {
            alone_end = end;
            alone = g;
        }
        // Ties go to the lower device index: the CPU first, where it is listed first.
        if (end < best_end) {
            best_end = end;
            best = g;
        }
    }
    if (best.device < 0) throw Error("no device of the node can hold a task of size " + std::to_string(request.size));
    // The device chosen takes a batch: as many tasks as end no later than
    // the task would alone elsewhere (all it may take where nowhere else can).
    // Where the task could run alone elsewhere, a device that has not run
    // the task yet takes one: its guess could be far off, and one task
    // teaches it the most; one that has run only batches of one size takes
    // at most kLearningBatch, which teaches it how a batch's time grows.
    const PerformanceModel* known = model(request.kind, best.device);
    int most_here = most(static_cast<std::size_t>(best.device));
    if (std::isfinite(alone_end) || request.alone_elsewhere_later) {
        if (!known) most_here = 1;
        else if (known->sizes() < 2) most_here = std::min(most_here, kLearningBatch);
    }
    for (int count = most_here; count > 1; --count) {
        const Grant g = candidate(request, best.device, count, now);
        if (g.start + g.predicted_seconds <= alone_end) {
            best = g;
            break;
        }
    }
    // A batch cut short by where the task would end alone, that would wait
    // behind the device's other grants and whose tasks would each take more
    // than kRemainderWaste times a full batch's share, goes there alone
    // instead. Such a remainder spends a batch's fixed cost on a few tasks
    // (on the N = 1000 job a batch of one took 0.12 s of a GPU, a task of a
    // batch of 32 0.034 s), and the device loses nothing by waiting for a
    // full batch: busy until then, it asks for one as soon as it is idle.
    // A device idle now still takes the remainder.
    if (best.count < most_here && best.start > now && alone.device >= 0 && alone.device != best.device) {
        const Grant full = candidate(request, best.device, most_here, now);
        if (best.predicted_seconds * most_here > kRemainderWaste * full.predicted_seconds * best.count) best = alone;
    }
    return book(best, request);
}

Grant ResourceManager::book(Grant grant, const ResourceRequest& request) {
    grant.ticket = next_ticket_++;
    Booking booking;
    booking.device = grant.device;
    booking.units = request.units[static_cast<std::size_t>(grant.device)];
    booking.start = grant.start;
    booking.end = grant.start + grant.predicted_seconds;
    booking.request = request;
    booking.request.size = request.size * grant.count;
    booking.count = grant.count;
    bookings_[grant.ticket] = booking;
    return grant;
}

double ResourceManager::in_use(int device) const {
    double units = 0;
    for (const auto& [ticket, b] : bookings_)
        if (b.device == device && b.started) units += b.units;
    return units;
}

bool ResourceManager::start(int ticket, double now) {
    const auto it = bookings_.find(ticket);
    if (it == bookings_.end()) throw Error("resource grant " + std::to_string(ticket) + " is not open");
    Booking& b = it->second;
    if (b.started) return true;
    for (const auto& [other, o] : bookings_) {
        if (other >= ticket) break;
        if (o.device == b.device && !o.started) return false; // served in order
    }
    if (in_use(b.device) + b.units > devices_[static_cast<std::size_t>(b.device)].capacity) return false;
    const double duration = b.end - b.start;
    b.started = true;
    b.start = now;
    b.end = now + duration;
    return true;
}

void ResourceManager::cancel(int ticket) { bookings_.erase(ticket); }

std::optional<Grant> ResourceManager::move(int ticket, int device, double now) {
    const auto it = bookings_.find(ticket);
    if (it == bookings_.end() || it->second.started || it->second.device == device) return std::nullopt;
    const Booking old = it->second;
    const auto d = static_cast<std::size_t>(device);
    if (d >= devices_.size() || d >= old.request.units.size()) return std::nullopt;
    const double units = old.request.units[d];
    if (!(units > 0) || units > devices_[d].capacity) return std::nullopt;
    ResourceRequest one = old.request;
    one.size = old.request.size / old.count;
    const Grant g = candidate(one, device, old.count, now);
    // Where the old booking's start has passed, it starts no earlier than now.
    const double old_end = std::max(old.start, now) + (old.end - old.start);
    if (!(g.start + g.predicted_seconds < old_end)) return std::nullopt;
    bookings_.erase(it);
    return book(g, one);
}

void ResourceManager::finish(int ticket, double seconds, double transfer_seconds) {
    const auto it = bookings_.find(ticket);
    if (it == bookings_.end() || !it->second.started) throw Error("resource grant " + std::to_string(ticket) + " did not start");
    const Booking& b = it->second;
    models_[{b.request.kind, b.device}].add(b.request.size, seconds);
    if (transfer_seconds > 0) {
        transfer_seconds_[static_cast<std::size_t>(b.device)] += transfer_seconds;
        transfer_size_[static_cast<std::size_t>(b.device)] += std::max(b.request.size, 1.0);
    }
    bookings_.erase(it);
}

} // namespace tetiso
