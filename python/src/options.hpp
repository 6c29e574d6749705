// Keyword arguments checked as the command line checks the options of the
// same name (core/cli/common.cpp), with the same words: "phi: 0 is outside
// (0, 1]" where the CLI says "--phi: 0 is outside (0, 1]". The library checks
// them again where it takes them.
#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "tetiso/device.hpp"
#include "tetiso/error.hpp"
#include "tetiso/mesh.hpp"

namespace tetiso::python {

// Messages write numbers as Python prints them, shortest first.
inline std::string number_text(double value) {
    if (std::isnan(value)) return "nan";
    if (std::isinf(value)) return value < 0 ? "-inf" : "inf";
    char text[32];
    for (int digits = 1; digits <= 17; ++digits) {
        std::snprintf(text, sizeof text, "%.*g", digits, value);
        if (std::strtod(text, nullptr) == value) break;
    }
    return text;
}

inline double checked_phi(double phi) {
    if (!(phi > 0 && phi <= 1)) throw Error("phi: " + number_text(phi) + " is outside (0, 1]");
    return phi;
}

inline double checked_error_bound(double bound, const char* name = "max_error") {
    if (!std::isfinite(bound)) throw Error(std::string(name) + ": " + number_text(bound) + " is not a finite bound (0 means none)");
    if (bound < 0) throw Error(std::string(name) + ": must be at least 0, not " + number_text(bound));
    return bound;
}

inline int checked_threads(int threads) {
    if (threads < 0 || threads > kMaxThreads)
        throw Error("threads: " + std::to_string(threads) + " is outside 0 (all cores) to " + std::to_string(kMaxThreads));
    return threads;
}

inline std::optional<double> checked_level(std::optional<double> level) {
    if (!level) return level;
    if (std::isnan(*level)) throw Error("level: a level must be a number, not nan");
    if (std::abs(*level) > std::numeric_limits<float>::max())
        throw Error("level: " + number_text(*level) +
                    " does not fit a float (the field's values are floats, of magnitude at most 3.4e38)");
    return level;
}

inline int checked_count(int count, const char* name) {
    if (count < 1) throw Error(std::string(name) + ": must be at least 1, not " + std::to_string(count));
    return count;
}

inline int checked_rings(int rings, const char* name) {
    if (rings < 0) throw Error(std::string(name) + ": must be at least 0, not " + std::to_string(rings));
    return rings;
}

// The device a call runs on, held for the call: one CUDA Device per GPU is
// made on first use and kept (its stream and buffers), and since one thread
// at a time may use it, calls from several Python threads take turns on it.
class DeviceUse {
public:
    // Throws tetiso::Error for a device other than "cpu" or "gpu", a GPU
    // index given with the CPU, or a GPU that is not there. Call it with the
    // GIL released: it may wait for another call on the same GPU.
    DeviceUse(const std::string& device, int gpu) {
        if (device == "cpu") {
            if (gpu != 0) throw Error("gpu: applies with device='gpu'; the work runs on the CPU");
            return;
        }
        if (device != "gpu") throw Error("device: '" + device + "' is neither 'cpu' nor 'gpu'");
        if (gpu < 0) throw Error("gpu: must be at least 0, not " + std::to_string(gpu));
        static std::mutex table_lock;
        // Never destroyed: at the process's exit the CUDA runtime may be
        // gone before static destructors would free the devices' buffers.
        static auto* devices = new std::map<int, std::pair<Device, std::unique_ptr<std::mutex>>>;
        std::pair<Device, std::unique_ptr<std::mutex>>* entry = nullptr;
        {
            std::lock_guard<std::mutex> guard(table_lock);
            auto found = devices->find(gpu);
            if (found == devices->end()) {
                const GpuInfo info = gpu_info(gpu);
                if (!info.available) throw Error("device gpu: " + info.description);
                found = devices->emplace(gpu, std::make_pair(Device::cuda(gpu), std::make_unique<std::mutex>())).first;
            }
            entry = &found->second;
        }
        turn_ = std::unique_lock<std::mutex>(*entry->second);
        device_ = entry->first;
    }
    const Device& device() const { return device_; }

private:
    Device device_;
    std::unique_lock<std::mutex> turn_;
};

} // namespace tetiso::python
