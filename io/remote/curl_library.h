// libcurl, loaded the first time remote data is read instead of linked. Linked, it and what it
// brings (TLS, Kerberos, LDAP, HTTP/2, SSH: about 25 libraries) cost every vdiso process and
// every `import vdiso` about 5 ms at start, local data or not: an eighth of a CT closeup's whole
// run. The readers of remote stores (io/remote/) call libcurl through this table only.
//
// curlLibrary() opens libcurl.so.4 (the library Debian's libcurl4-openssl-dev builds against),
// or the file VDISO_CURL_LIBRARY names, once, thread-safely, and runs curl_global_init; it
// throws IoError when either fails, saying what remote reading needs. Each member has the type of the libcurl function of its name.
#pragma once

#include <curl/curl.h>

#include <string>

namespace vdiso {

struct CurlLibrary {
    decltype(&::curl_global_init) global_init;
    decltype(&::curl_easy_init) easy_init;
    decltype(&::curl_easy_setopt) easy_setopt;
    decltype(&::curl_easy_perform) easy_perform;
    decltype(&::curl_easy_getinfo) easy_getinfo;
    decltype(&::curl_easy_cleanup) easy_cleanup;
    decltype(&::curl_easy_strerror) easy_strerror;
    decltype(&::curl_share_init) share_init;
    decltype(&::curl_share_setopt) share_setopt;
    decltype(&::curl_share_cleanup) share_cleanup;
    decltype(&::curl_slist_append) slist_append;
    decltype(&::curl_slist_free_all) slist_free_all;
    decltype(&::curl_url) url;
    decltype(&::curl_url_set) url_set;
    decltype(&::curl_url_get) url_get;
    decltype(&::curl_url_cleanup) url_cleanup;
    decltype(&::curl_free) free;
    decltype(&::curl_getdate) getdate;
};

const CurlLibrary& curlLibrary();
// curlLibrary(), its failure an IoError naming `location` (the URL about to be read).
const CurlLibrary& curlLibraryFor(const std::string& location);

}  // namespace vdiso
