// An s3://BUCKET/KEY location resolved to an HTTP request: the endpoint and addressing, the
// region, and the credentials (AWS's own order: the environment, then the shared credentials
// file's profile), for libcurl's SigV4 signing (io/remote/remote_file.h).
#pragma once

#include <string>

#include "io/remote/remote_options.h"

namespace vdiso {

struct S3Location {
    std::string bucket, key;
    std::string url;     // the object's http(s) URL, path or virtual-host style
    std::string base;    // url without the encoded key: the bucket's URL, ending in '/' 
    std::string region;  // signing region
    // Empty access key: anonymous (unsigned) requests.
    std::string accessKey, secretKey, sessionToken;
};

// Throws IoError naming the URL when it is not s3://BUCKET/KEY, or when a credentials file
// named by the environment cannot be read.
S3Location resolveS3Location(const std::string& s3Url, const RemoteOptions& options);

// The same bucket's location for another key: endpoint, addressing, region and credentials as
// resolved for `bucket` (RemoteSession resolves a bucket once, not once per object).
S3Location withKey(const S3Location& bucket, const std::string& key);

// s3://BUCKET/KEY split; throws IoError naming the URL when it is not one.
void splitS3Url(const std::string& s3Url, std::string& bucket, std::string& key);

// The key URI-encoded as S3 signs it: every byte but A-Z a-z 0-9 - . _ ~ and '/' as %XX.
std::string s3EncodeKey(const std::string& key);

}  // namespace vdiso
