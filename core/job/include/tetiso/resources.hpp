// The resource manager of one node (paper, section "Load balancing and job
// scheduling"): one counter per device, the node's CPU processes and each of
// its GPUs, and a choice of device per task that minimises the time at which
// the task would end there.
//
// A request names the units it needs on each device it may run on, in
// whatever units the caller counts (placement.hpp: CPU worker processes, and
// one task slot per GPU). The manager predicts the task's seconds τ_i on each
// device from the tasks that finished there (PerformanceModel; while a
// device has too few to trust, the rate of those it has, else a prior the
// caller set, and no less than its tasks of that kind have been running),
// finds the time t_b,i at which counter i admits the request, and grants the
// device with the smallest t_b,i + τ_i. Grants are decided in the order requests arrive, and
// none is placed on a device before one granted earlier there: a waiting
// client is served in order and a large request is not starved by small
// ones. The manager never lets a device's units in use exceed its capacity:
// a grant only starts (start()) when its units are free now, whatever was
// predicted.
//
// Batches. A request may let a device take up to k tasks like it at once
// (a GPU reduces several domains side by side): on such a device the grant
// carries the most tasks c <= k whose batch, of c times the size, ends no
// later than the request would end on a device that takes one task alone,
// so that a device that finishes a task first still gets it; where no such
// device can hold the request, c = k; where the task could run alone
// elsewhere, c = 1 on a device that has not run the task yet and
// c <= kLearningBatch on one whose grants were all of one size. The models
// learn the batch's time as a function of its size; until a device's model
// has seen two sizes, a batch is assumed to take as long as its tasks one
// after another.
//
// Pure and clock-injected: the caller says what time it is, so that tests
// drive it with a simulated clock and the MPI controller with its own.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace tetiso {

// Seconds a kind of task takes on one device as a function of its size,
// learnt from the tasks that finished there. Like StarPU's history-based
// model, a size seen kMinSamples times is predicted by the mean of its
// samples; like its non-linear regression model, any other size, once
// kMinSamples samples of at least two sizes exist, by a fit of
// seconds = a * size^b (least squares in log-log space); with one size only,
// in proportion to size. Before that there is no prediction: the caller
// falls back to the rate of the first samples, a prior, another device's
// prediction or a default.
class PerformanceModel {
public:
    static constexpr int kMinSamples = 3;

    void add(double size, double seconds);
    std::optional<double> predict(double size) const;
    int samples() const { return samples_; }
    // Seconds per unit of size over every sample (nothing before the first):
    // what a device's own first tasks say before there are enough to trust.
    std::optional<double> rate() const {
        return samples_ > 0 ? std::optional<double>(total_ / total_size_) : std::nullopt;
    }
    // The different sizes among the samples.
    std::size_t sizes() const { return by_size_.size(); }

private:
    struct History {
        int count = 0;
        double sum = 0;
    };
    std::map<double, History> by_size_;
    int samples_ = 0;
    double total_ = 0, total_size_ = 0;
    // Sums for the regression of log(seconds) on log(size).
    double sx_ = 0, sy_ = 0, sxx_ = 0, sxy_ = 0;
};

struct ManagedDevice {
    std::string name;    // "cpu", "gpu 0", ...
    int gpu = -1;        // the CUDA index, -1 for the CPU
    double capacity = 1; // units: processes for the CPU, task slots for a GPU
    // Seconds to move one unit of a task's size to the device and its result
    // back, added to the model's τ (StarPU's dmda counts transfers the same
    // way): the value to assume until a task has finished there, after which
    // the mean of the measured ones is used; 0 for the CPU.
    double transfer_per_size = 0;
};

struct ResourceRequest {
    int kind = 0;       // which performance model: a task kind
    double size = 1;    // the task's size, the models' variable
    // Units needed on each device, in the manager's device order; a value
    // <= 0 means the task cannot run there.
    std::vector<double> units;
    // The most tasks like this one a device may take in one grant, in the
    // manager's device order; missing or below 2: one.
    std::vector<int> batch = {};
    // A device that cannot take the task now will soon take it alone (it
    // waits for its prior): a device still learning the task takes batches
    // as small as if it could.
    bool alone_elsewhere_later = false;
};

struct Grant {
    int ticket = -1;
    int device = -1;             // index into the manager's devices
    double start = 0;            // t_b: when the device admits the request
    double predicted_seconds = 0; // τ on that device, for the whole batch
    int count = 1;               // tasks the grant carries (ResourceRequest::batch)
};

class ResourceManager {
public:
    // Seconds assumed for a kind of task on a device whose model has too few
    // samples and with no other device's to go by: low, so that every device
    // is tried early and gets a model (StarPU calibrates the same way).
    static constexpr double kUncalibratedSeconds = 1e-3;
    // A device not calibrated for a kind of task that another device is is
    // assumed this many times faster than the fastest of those: enough to be
    // tried (an equal guess would lose every tie to the device listed first,
    // and never learn), not so much that it is flooded meanwhile.
    static constexpr double kUncalibratedSpeedup = 2;
    // The most tasks of a batch on a device whose batches so far were all of
    // one size (request()).
    static constexpr int kLearningBatch = 8;
    // A batch smaller than the most a device may take, that would wait
    // behind its other grants, is granted only while its tasks take at most
    // this many times their share of a full batch (request()).
    static constexpr double kRemainderWaste = 1.25;

    explicit ResourceManager(std::vector<ManagedDevice> devices);

    const std::vector<ManagedDevice>& devices() const { return devices_; }

    // Decides where and when the request runs, at time `now`; books its
    // units on that device from grant.start for the predicted seconds.
    // Throws tetiso::Error when no device can hold it.
    Grant request(const ResourceRequest& request, double now);

    // Whether the grant may start now: its device has the units free now
    // and every grant booked before it there has started. True marks it
    // started (its units in use) — call until it is.
    bool start(int ticket, double now);

    // The task of a started grant ended after `seconds` of work on the
    // device and `transfer_seconds` moving its data there and back: its
    // units are free, the model of its kind on its device learns the work,
    // and the device's transfer rate the transfer.
    void finish(int ticket, double seconds, double transfer_seconds = 0);

    // Drops a grant, started or not, without learning from it (its task
    // failed, or the job stopped before it ran).
    void cancel(int ticket);

    // Moves a grant that has not started to `device`, where it would end
    // before its booking's end: the grant there (a new ticket; the old one
    // is closed), or nothing where the grant cannot run there or would not
    // end earlier. For a device that is idle while another works through
    // grants booked on predictions that ran long.
    std::optional<Grant> move(int ticket, int device, double now);

    // Units in use on a device now (started grants).
    double in_use(int device) const;

    // The prediction for a kind and size on a device, as request() makes it.
    double predict(int kind, double size, int device) const;

    // What a kind of task is assumed to take on a device before the device
    // has a sample of its own: seconds_per_size x size (StarPU's calibration
    // run, made by the caller some other way: NodePlacement scales a probe
    // of the CPU by the size of the job's domains). A device's own samples
    // replace it from the first.
    void set_prior(int kind, int device, double seconds_per_size);
    bool has_prior(int kind, int device) const { return priors_.count({kind, device}) > 0; }

    const PerformanceModel* model(int kind, int device) const;

private:
    struct Booking {
        int device = -1;
        double units = 0;
        double start = 0, end = 0; // predicted, while not started; end stays predicted
        bool started = false;
        ResourceRequest request; // its size the whole grant's
        int count = 1;           // the tasks of the grant
    };
    // The seconds request() expects the task to take on `device` at `now`:
    // the model's prediction, and where the model has too few samples, at
    // least as long as any task of its kind has been running there.
    double expected_seconds(const ResourceRequest& request, int device, double now) const;
    // Where and when `request` (one task, or `count` as a batch) would run
    // on `device`.
    Grant candidate(const ResourceRequest& request, int device, int count, double now) const;
    // Books `grant` (its device, start, seconds and count) for `request`, one
    // task's: the grant with its ticket.
    Grant book(Grant grant, const ResourceRequest& request);
    // When device `d` could admit `units` for `seconds`, at `now` or later.
    double admission_time(int device, double units, double seconds, double now) const;
    double units_booked_at(int device, double time, double now) const;
    // The device's own say on the task: its model once calibrated, else the
    // rate of its first samples times the size, else its prior; nothing
    // where it has none.
    std::optional<double> estimate(int kind, double size, int device) const;

    std::vector<ManagedDevice> devices_;
    std::map<std::pair<int, int>, PerformanceModel> models_; // (kind, device)
    std::map<std::pair<int, int>, double> priors_;           // (kind, device) -> seconds per unit of size
    std::map<int, Booking> bookings_;                        // ticket -> booking, open ones
    std::vector<double> transfer_seconds_, transfer_size_;    // per device, measured so far
    int next_ticket_ = 0;
};

} // namespace tetiso
