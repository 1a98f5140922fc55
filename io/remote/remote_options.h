// How remote stores are reached (io/remote/remote_file.h): what a front end gathers from its
// flags and the environment, and passes down with the URL.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>

namespace vdiso {

enum class S3Addressing { Auto, Path, VirtualHost };

struct RemoteOptions {
    // s3:// URLs: the endpoint ("https://s3.eu-west-1.amazonaws.com", "http://127.0.0.1:9000");
    // empty: AWS_ENDPOINT_URL_S3 or AWS_ENDPOINT_URL, else AWS's endpoint for the region.
    std::string s3Endpoint;
    // Auto: virtual-host style on AWS's own endpoints, path style on any other endpoint (as
    // MinIO, Ceph and most local servers want).
    S3Addressing s3Addressing = S3Addressing::Auto;
    // Requests without credentials even when some are found (public buckets).
    bool anonymous = false;
    // A file of CA certificates for HTTPS instead of the system's (AWS_CA_BUNDLE when empty).
    std::string caFile;
    // Requests in flight at once (the connection pool's size).
    int connections = 32;
    // Attempts of a request that failed on a 5xx, a timeout or a broken connection.
    int attempts = 4;
    // Milliseconds to connect, and without a byte received before a request is a straggler.
    int64_t connectTimeoutMs = 10000;
    int64_t stallTimeoutMs = 15000;
    // Milliseconds one read may take in all, its tries, pauses and redirects included: a server
    // that sends a byte now and then never trips the stall timeout, and is ended by this.
    int64_t deadlineMs = 60000;
    // A folder keeping fetched ranges across runs and processes (io/remote/disk_cache.h); empty:
    // none. At most diskCacheBytes are kept.
    std::string diskCacheDir;
    uint64_t diskCacheBytes = uint64_t(10) << 30;
    // Once set to true, every read in flight ends within a second (libcurl asks about once a
    // second) and later ones fail at once: a server stopping. Null: reads end only by themselves
    // or by the process's interrupt (core/interrupt.h).
    std::shared_ptr<const std::atomic<bool>> stop;
    // Follow 3xx answers (at most 8; with credentials only to the same scheme, host and port).
    // Off where the answers are untrusted test input (fuzz).
    bool followRedirects = true;
};

}  // namespace vdiso
