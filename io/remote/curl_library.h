// libcurl, loaded the first time remote data is read instead of linked. Linked, it and what it
// brings (TLS, Kerberos, LDAP, HTTP/2, SSH: about 25 libraries) cost every vdiso process and
// every `import vdiso` about 5 ms at start, local data or not: an eighth of a CT closeup's whole
// run. The readers of remote stores (io/remote/) call libcurl through this table only.
//
// curlLibrary() opens libcurl.so.4 (the library Debian's libcurl4-openssl-dev builds against),
// or the file VDISO_CURL_LIBRARY names, once, thread-safely, and runs curl_global_init; it
// throws IoError when either fails, saying what remote reading needs. Each member has the type
// of the libcurl function of its name (curl_ and the member's name), as the renderer's table of
// OSMesa's functions does (io/render/renderer.cpp).
#pragma once

#include <curl/curl.h>

#include <string>

namespace vdiso {

#define VDISO_CURL_FUNCTIONS(X)                                                                    \
    X(global_init) X(easy_init) X(easy_setopt) X(easy_getinfo) X(easy_cleanup)                     \
    X(easy_strerror) X(share_init) X(share_setopt) X(share_cleanup) X(slist_append)               \
    X(slist_free_all) X(url) X(url_set) X(url_get) X(url_cleanup) X(free) X(getdate)               \
    X(multi_init) X(multi_cleanup) X(multi_setopt) X(multi_add_handle) X(multi_remove_handle)      \
    X(multi_socket_action) X(multi_info_read)

struct CurlLibrary {
#define VDISO_CURL_MEMBER(name) decltype(&::curl_##name) name = nullptr;
    VDISO_CURL_FUNCTIONS(VDISO_CURL_MEMBER)
#undef VDISO_CURL_MEMBER
};

const CurlLibrary& curlLibrary();
// curlLibrary(), its failure an IoError naming `location` (the URL about to be read).
const CurlLibrary& curlLibraryFor(const std::string& location);

}  // namespace vdiso
