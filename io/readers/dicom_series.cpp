#include "io/readers/dicom_series.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>

#include <glm/geometric.hpp>

#include "core/orientation.h"
#include "io/error.h"

namespace vdiso {
namespace {

// How far a step may be from the median step, as a fraction of it: positions are written with
// a few decimals, a missing slice is a whole step off.
constexpr double kStepTolerance = 0.01;
// Orientation cosines that differ by less than this are the same orientation.
constexpr double kCosineTolerance = 1e-4;

std::string formatNumber(double v) {
    char text[32];
    std::snprintf(text, sizeof(text), "%.6g", v);
    return text;
}

std::string sliceFormat(const DicomHeader& h) {
    return std::to_string(h.columns) + " x " + std::to_string(h.rows) + " " +
           fileScalarName(h.pixelType);
}

struct SeriesSummary {
    std::string description, modality;
    size_t slices = 0;
    uint32_t columns = 0, rows = 0;
    bool mixedSizes = false;
};

std::string seriesList(const std::vector<DicomHeader>& headers) {
    std::map<std::string, SeriesSummary> series;
    for (const DicomHeader& h : headers) {
        SeriesSummary& s = series[h.seriesUid];
        if (s.slices == 0) {
            s.description = h.seriesDescription;
            s.modality = h.modality;
            s.columns = h.columns;
            s.rows = h.rows;
        } else if (s.columns != h.columns || s.rows != h.rows) {
            s.mixedSizes = true;
        }
        ++s.slices;
    }
    std::string text;
    for (const auto& [uid, s] : series) {
        text += "\n  " + (uid.empty() ? std::string("(no SeriesInstanceUID)") : uid) + "  \"" +
                s.description + "\"  " + (s.modality.empty() ? "?" : s.modality) + "  " +
                std::to_string(s.slices) + (s.slices == 1 ? " slice  " : " slices  ") +
                std::to_string(s.columns) + " x " + std::to_string(s.rows) +
                (s.mixedSizes ? " (and other sizes)" : "");
    }
    return text;
}

size_t seriesCount(const std::vector<DicomHeader>& headers) {
    std::vector<std::string> uids;
    for (const DicomHeader& h : headers) uids.push_back(h.seriesUid);
    std::sort(uids.begin(), uids.end());
    return size_t(std::unique(uids.begin(), uids.end()) - uids.begin());
}

glm::dvec3 rowDirection(const std::array<double, 6>& o) { return {o[0], o[1], o[2]}; }
glm::dvec3 columnDirection(const std::array<double, 6>& o) { return {o[3], o[4], o[5]}; }

bool sameOrientation(const std::array<double, 6>& a, const std::array<double, 6>& b) {
    for (int i = 0; i < 6; ++i)
        if (!(std::abs(a[i] - b[i]) <= kCosineTolerance)) return false;
    return true;
}

void checkSameFormat(const std::vector<DicomHeader>& slices, const std::string& where) {
    const DicomHeader& first = slices.front();
    for (const DicomHeader& h : slices)
        if (h.rows != first.rows || h.columns != first.columns || h.pixelType != first.pixelType)
            throwIoError(where, "slice " + h.path + " is " + sliceFormat(h) + ", unlike the " +
                                    sliceFormat(first) + " of " + first.path +
                                    ": every slice of a series must have the same size and type");
}

// Sorts by position along the normal and returns the z step; refuses gaps, duplicates, shear.
double orderByPosition(std::vector<DicomHeader>& slices, const std::string& where) {
    const std::array<double, 6>& o = *slices.front().orientation;
    for (const DicomHeader& h : slices)
        if (!sameOrientation(*h.orientation, o))
            throwIoError(where, "slice " + h.path +
                                    " has another ImageOrientationPatient than " +
                                    slices.front().path + ": a series must keep one orientation");
    glm::dvec3 normal = glm::cross(rowDirection(o), columnDirection(o));
    const double length = glm::length(normal);
    if (!(length > 0.5 && length < 1.5))
        throwIoError(where, "ImageOrientationPatient of " + slices.front().path +
                                " is not two unit directions at right angles");
    normal /= length;
    auto along = [&](const DicomHeader& h) { return glm::dot(*h.position, normal); };
    std::stable_sort(slices.begin(), slices.end(),
                     [&](const DicomHeader& a, const DicomHeader& b) { return along(a) < along(b); });
    std::vector<double> steps;
    for (size_t i = 1; i < slices.size(); ++i) steps.push_back(along(slices[i]) - along(slices[i - 1]));
    std::vector<double> sorted = steps;
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const double median = sorted[sorted.size() / 2];
    for (size_t i = 0; i < steps.size(); ++i) {
        const DicomHeader& a = slices[i];
        const DicomHeader& b = slices[i + 1];
        if (!(steps[i] > 1e-6 * std::max(1.0, median)))
            throwIoError(where, "slices " + a.path + " and " + b.path +
                                    " lie at the same position " + formatNumber(along(a)) +
                                    " along the slice normal (several acquisitions in one "
                                    "series?): choose the files of one");
    }
    for (size_t i = 0; i < steps.size(); ++i) {
        if (std::abs(steps[i] - median) <= kStepTolerance * median) continue;
        const DicomHeader& a = slices[i];
        const DicomHeader& b = slices[i + 1];
        const double ratio = steps[i] / median;
        const std::string what = ratio > 1.5 ? "a slice is missing" : "the slices are unevenly spaced";
        throwIoError(where, "a gap of " + formatNumber(steps[i]) + " mm between slice " + a.path +
                                " (at " + formatNumber(along(a)) + ") and " + b.path + " (at " +
                                formatNumber(along(b)) + "), where the other slices are " +
                                formatNumber(median) + " mm apart: " + what +
                                "; vdiso needs evenly spaced slices");
    }
    const double step = (along(slices.back()) - along(slices.front())) / double(slices.size() - 1);
    if (!(std::isfinite(step) && step > 0.0 && step < 1e12))
        throwIoError(where, "the slice positions give a step of " + formatNumber(step));
    // The stack must advance along its normal: a sideways drift is a sheared grid.
    const glm::dvec3 advance = *slices.back().position - *slices.front().position;
    const glm::dvec3 sideways = advance - glm::dot(advance, normal) * normal;
    if (glm::length(sideways) > kStepTolerance * step * double(slices.size() - 1) + 1e-3) {
        const double degrees =
            std::atan2(glm::length(sideways), glm::dot(advance, normal)) * 180.0 / M_PI;
        throwIoError(where, "the slice positions drift sideways from the slice normal by " +
                                formatNumber(degrees) +
                                " degrees (gantry tilt?): a sheared stack is not supported");
    }
    return step;
}

double orderByInstance(std::vector<DicomHeader>& slices, const std::string& where) {
    const std::optional<double>& given = slices.front().sliceSpacing;
    const double spacing = given && std::isfinite(*given) && *given > 0.0 ? *given : 1.0;
    if (slices.size() == 1) return spacing;
    for (const DicomHeader& h : slices)
        if (!h.instanceNumber)
            throwIoError(where, "slice " + h.path +
                                    " has neither ImagePositionPatient and "
                                    "ImageOrientationPatient nor InstanceNumber to order it by");
    std::stable_sort(slices.begin(), slices.end(), [](const DicomHeader& a, const DicomHeader& b) {
        return *a.instanceNumber < *b.instanceNumber;
    });
    for (size_t i = 1; i < slices.size(); ++i)
        if (*slices[i].instanceNumber == *slices[i - 1].instanceNumber)
            throwIoError(where, "slices " + slices[i - 1].path + " and " + slices[i].path +
                                    " have the same InstanceNumber and no position");
    return spacing;
}

// The range of stored values a slice's pixels may hold, from BitsStored.
void storedRange(const DicomHeader& h, double& lo, double& hi) {
    const int allocated = int(fileScalarSize(h.pixelType)) * 8;
    const int bits = h.bitsStored >= 1 && h.bitsStored <= allocated ? h.bitsStored : allocated;
    const bool isSigned = h.pixelType == FileScalar::I8 || h.pixelType == FileScalar::I16 ||
                          h.pixelType == FileScalar::I32;
    if (isSigned) {
        lo = -std::ldexp(1.0, bits - 1);
        hi = std::ldexp(1.0, bits - 1) - 1.0;
    } else {
        lo = 0.0;
        hi = std::ldexp(1.0, bits) - 1.0;
    }
}

bool isInteger(double v) { return std::isfinite(v) && v == std::floor(v) && std::abs(v) < 1e9; }

ScalarType storeType(const std::vector<DicomHeader>& slices, bool& scaled, const std::string& where) {
    scaled = false;
    bool integral = true;
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const DicomHeader& h : slices) {
        if (!std::isfinite(h.slope) || !std::isfinite(h.intercept) || h.slope == 0.0)
            throwIoError(where, "slice " + h.path + " has RescaleSlope " + formatNumber(h.slope) +
                                    " and RescaleIntercept " + formatNumber(h.intercept));
        if (h.slope != 1.0 || h.intercept != 0.0) scaled = true;
        if (!isInteger(h.slope) || !isInteger(h.intercept)) integral = false;
        double a, b;
        storedRange(h, a, b);
        a = a * h.slope + h.intercept;
        b = b * h.slope + h.intercept;
        lo = std::min({lo, a, b});
        hi = std::max({hi, a, b});
    }
    if (!scaled) return storeTypeFor(slices.front().pixelType, false);
    if (integral && lo >= -32768.0 && hi <= 32767.0) return ScalarType::I16;
    return ScalarType::F32;
}

}  // namespace

std::vector<DicomHeader> selectDicomSeries(std::vector<DicomHeader> headers,
                                           const std::string& seriesUid, const std::string& where) {
    if (headers.empty()) throwIoError(where, "holds no DICOM image");
    if (seriesUid.empty()) {
        if (seriesCount(headers) == 1) return headers;
        throw DicomSeriesChoiceError(where + ": holds " + std::to_string(seriesCount(headers)) +
                                     " series; choose one by its SeriesInstanceUID:" + seriesList(headers));
    }
    std::vector<DicomHeader> chosen;
    for (DicomHeader& h : headers)
        if (h.seriesUid == seriesUid) chosen.push_back(std::move(h));
    if (chosen.empty())
        throwIoError(where, "holds no series " + seriesUid + "; it holds:" + seriesList(headers));
    return chosen;
}

DicomVolume arrangeDicomSeries(std::vector<DicomHeader> slices, const std::string& where,
                               size_t minSlices) {
    if (slices.size() < std::max<size_t>(minSlices, 1))
        throwIoError(where, "the series has " + std::to_string(slices.size()) +
                                " slice: a volume needs at least 2");
    checkSameFormat(slices, where);
    const bool placed = slices.size() > 1 &&
                        std::all_of(slices.begin(), slices.end(), [](const DicomHeader& h) {
                            return h.position && h.orientation;
                        });
    DicomVolume v;
    const double step = placed ? orderByPosition(slices, where) : orderByInstance(slices, where);
    const DicomHeader& first = slices.front();
    v.info.dims = {int64_t(first.columns), int64_t(first.rows), int64_t(slices.size())};
    if (slices.size() > 1) requireVolumeDims(where, v.info.dims);
    else requireVolumeDims(where, {v.info.dims[0], v.info.dims[1], 2});
    v.info.type = storeType(slices, v.scaled, where);
    v.info.spacing = glm::dvec3(1.0, 1.0, step);
    if (first.pixelSpacing) {
        const auto& s = *first.pixelSpacing;
        if (std::isfinite(s[1]) && s[1] > 0.0) v.info.spacing.x = s[1];
        if (std::isfinite(s[0]) && s[0] > 0.0) v.info.spacing.y = s[0];
    }
    if (first.position) v.info.origin = *first.position;
    if (placed) {
        // PS3.3 C.7.6.2.1.1: the row cosines are the direction of increasing column (our i),
        // the column cosines that of increasing row (j); slices run along their cross product,
        // the order orderByPosition sorted them in (k). ImagePositionPatient is LPS already.
        const std::array<double, 6>& o = *first.orientation;
        const glm::dvec3 row = glm::normalize(rowDirection(o)), column = glm::normalize(columnDirection(o));
        const glm::dmat3 direction(row, column, glm::normalize(glm::cross(row, column)));
        if (const std::string problem = directionProblem(direction); !problem.empty())
            throwIoError(where, "ImageOrientationPatient of " + first.path + ": " + problem);
        v.info.direction = direction;
        v.info.hasOrientation = true;
    }
    v.slices = std::move(slices);
    return v;
}

}  // namespace vdiso
