// A setting out of range or at odds with the others, said in words that name quantities, not
// flags: setting() is its name in snake case ("lod_error"), what() the rest of the sentence
// ("expects pixels, 0 or more, not -1"). Each front end puts its own spelling in front
// (vdiso: "--lod-error", Python: "lod_error") and treats it as wrong usage.
#pragma once

#include <stdexcept>
#include <string>

namespace vdiso {

class SettingsError : public std::invalid_argument {
public:
    SettingsError(std::string setting, const std::string& rest)
        : std::invalid_argument(rest), mSetting(std::move(setting)) {}
    const std::string& setting() const { return mSetting; }

private:
    std::string mSetting;
};

}  // namespace vdiso
