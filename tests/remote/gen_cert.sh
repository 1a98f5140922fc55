#!/bin/sh
# Make a throw-away self-signed TLS certificate for the loopback test servers.
# usage: gen_cert.sh OUTDIR [NAME]   -> OUTDIR/NAME.crt, OUTDIR/NAME.key (NAME=server)
# The certificate is its own CA: give NAME.crt to the client as CA file
# (curl --cacert, CURLOPT_CAINFO). A second call with another NAME gives an
# unrelated "wrong CA" for TLS-failure tests. Valid 2 days, for localhost,
# *.s3.localhost (virtual-host buckets), 127.0.0.1 and ::1.
set -eu
out=${1:?usage: gen_cert.sh OUTDIR [NAME]}
name=${2:-server}
mkdir -p "$out"
openssl req -x509 -newkey ec -pkeyopt ec_paramgen_curve:prime256v1 -nodes \
    -days 2 -subj "/CN=localhost" \
    -addext "subjectAltName=DNS:localhost,DNS:*.s3.localhost,IP:127.0.0.1,IP:::1" \
    -addext "basicConstraints=critical,CA:TRUE" \
    -keyout "$out/$name.key" -out "$out/$name.crt" 2>/dev/null
chmod 600 "$out/$name.key"
echo "$out/$name.crt $out/$name.key"
