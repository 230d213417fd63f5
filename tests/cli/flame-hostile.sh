#!/usr/bin/env bash
# Hostile .flame files are refused by their counts while they stream in, before anything large is
# built: 10^6 xforms in one flame in under 0.5 s of processor time and 50 MiB of peak memory (also
# under ulimit -v 1000000), with one line on stderr naming the file and line; likewise 10^6 palette
# entries, an attribute or a text of megabytes, 5000 flames, elements nested 100 deep, an entity
# declaration (no expansion: "billion laughs"), a file over 16 MiB; libxml2's own messages never
# reach stderr. A genome within the limits still renders, and flam3's palette library is still read.
# Usage: flame-hostile.sh PATH/TO/fractalbake
. "$(dirname "$0")/lib.sh"
cli_init "$@"
N="--backend native"
# A sanitizer build reserves terabytes of shadow memory and multiplies time and memory: there the
# refusals are checked (exit, the line, no output) without ulimit -v and without the bounds.
asan=0
sanitized && asan=1
C='<color index="0" rgb="255 0 0"/>'
X='<xform weight="1" coefs="1 0 0 1 0 0" linear="1"/>'

# refused NAME PATTERN MAX_SECONDS MAX_MIB [ULIMIT_V]: exit 2, one stderr line matching PATTERN, no
# output, within the time and the peak resident memory (GNU time's "Maximum resident set size"). The
# time is the processor's (user and system): the machine may be busy with other work, which
# stretches the wall-clock time without the refusal costing more.
refused() {
  local f=$1 pat=$2 secs=$3 mib=$4 lim=${5:-unlimited}
  [ $asan = 1 ] && [ "$lim" != unlimited ] && return 0
  (ulimit -v "$lim" && /usr/bin/time -v -o time.txt "$FB" flame $N --file "$f" --size 64x64 -o o.exr > out.txt 2> err.txt)
  local rc=$? s kib
  s=$(awk -F': ' '/User time \(seconds\)|System time \(seconds\)/ { t += $2 } END { print t }' time.txt)
  kib=$(sed -n 's/.*Maximum resident set size (kbytes): //p' time.txt)
  check "$f (ulimit -v $lim): exit $rc, wanted 2 ($(cat err.txt))" test $rc -eq 2
  check "$f (ulimit -v $lim): one stderr line, $(wc -l < err.txt) here" test "$(wc -l < err.txt)" -eq 1
  check "$f (ulimit -v $lim): the line names the file and says why: $(cat err.txt)" grep -q -- "$pat" err.txt
  if [ $asan = 0 ]; then
    check "$f (ulimit -v $lim): $s s of processor time, wanted under $secs" awk "BEGIN { exit !($s < $secs) }"
    check "$f (ulimit -v $lim): $((kib / 1024)) MiB peak, wanted under $mib" test "$kib" -lt $((mib * 1024))
  fi
  check "$f (ulimit -v $lim): no output, no temporary file" sh -c '! test -e o.exr && ! test -s out.txt' && no_temp_files
}

# 10^6 xforms in one flame (51 MB): read by the whole tree before, 8.8 s and 1.35 GB
python3 - << PY
x = '$X\n'
with open('xforms.flame', 'w') as f:
    f.write('<flames>\n<flame name="big" size="64 64">\n' + x * 1000000 + '$C\n</flame>\n</flames>\n')
with open('colors.flame', 'w') as f:
    f.write('<flame size="64 64">$X\n' + '<color index="0" rgb="255 0 0"/>\n' * 1000000 + '</flame>\n')
with open('attr.flame', 'w') as f:
    f.write('<flame size="64 64" notes="' + 'n' * (8 << 20) + '">$X$C</flame>\n')
with open('text.flame', 'w') as f:
    f.write('<flame size="64 64">$X<palette count="256" format="RGB">' + '00ff00' * 1000000 + '</palette></flame>\n')
with open('flames.flame', 'w') as f:
    f.write('<flames>' + '<flame size="64 64">$X$C</flame>\n' * 5000 + '</flames>\n')
with open('deep.flame', 'w') as f:
    f.write('<flame size="64 64">$X$C' + '<edit>' * 100 + '</edit>' * 100 + '</flame>\n')
with open('big.flame', 'w') as f:  # in 1 MiB comments, below libxml2's own limit on one
    f.write('<flame size="64 64">$X$C' + ('<!--' + ' ' * (1 << 20) + '-->') * 20 + '</flame>\n')
with open('attrs.flame', 'w') as f:
    f.write('<flame size="64 64"><xform weight="1" coefs="1 0 0 1 0 0" '
            + ' '.join('a%d="0"' % i for i in range(300)) + '/>$C</flame>\n')
PY
# billion laughs: ten levels of ten references each, 10^10 "lol"s if expanded
{
  echo '<?xml version="1.0"?>'
  echo '<!DOCTYPE flame [ <!ENTITY l0 "lol">'
  for i in $(seq 1 9); do printf '<!ENTITY l%d "%s">\n' $i "$(printf "&l$((i - 1));%.0s" $(seq 10))"; done
  echo ']>'
  echo "<flame size=\"64 64\" name=\"&l9;\">$X$C</flame>"
} > laughs.flame
printf '<flame size="64 64">%s%s<xform weight="1"\n coefs="1 0 0 1 0 0" linear="1"></flame>\n' "$X" "$C" > broken.flame

refused xforms.flame "xforms.flame:27: more than 24 xforms in one <flame>" 0.5 50
refused xforms.flame "xforms.flame:27: more than 24 xforms in one <flame>" 0.5 50 1000000
refused colors.flame "colors.flame:258: more than 256 palette elements" 0.5 50
refused colors.flame "colors.flame:258: more than 256 palette elements" 0.5 50 1000000
refused attr.flame "attr.flame:1: <flame notes>: a value of 8388608 bytes, more than 64 KiB" 0.5 50
refused text.flame "text.flame:1: more than 64 KiB of text in one element" 0.5 50
refused flames.flame "flames.flame:4097: more than 4096 <flame> elements" 0.5 50
refused deep.flame "deep.flame:1: <edit>: elements nested more than 64 deep" 0.5 50
refused big.flame "big.flame: larger than 16 MiB" 0.5 50
# the same through a pipe
"$FB" flame $N --file <(cat big.flame) --size 64x64 -o o.exr > out.txt 2> err.txt
check "big.flame through a pipe: exit $?, one line: $(cat err.txt)" \
  sh -c 'test "$(wc -l < err.txt)" -eq 1 && grep -q "larger than 16 MiB" err.txt && ! test -e o.exr'
refused attrs.flame "attrs.flame:1: <xform>: 302 attributes, more than 256" 0.5 50
refused laughs.flame "laughs.flame:2: declares the entity l0: entities are not expanded" 0.5 50
refused laughs.flame "laughs.flame:2: declares the entity l0: entities are not expanded" 0.5 50 1000000
refused broken.flame "broken.flame:2: not well-formed XML: " 0.5 50 1000000

# within the limits: 24 xforms, 256 <color>s, and flam3's palette library (palette="N")
python3 - << PY
with open('ok.flame', 'w') as f:
    f.write('<flames><flame size="64 64">' + '$X' * 24 + ''.join('<color index="%d" rgb="%d 0 0"/>' % (i, i) for i in range(256))
            + '</flame>\n<flame name="lib" size="64 64" palette="7">$X</flame></flames>\n')
PY
"$FB" flame $N --file ok.flame --size 32x32 -o ok.exr --quiet
check "24 xforms and 256 colours render" test $? -eq 0 -a -s ok.exr
if [ -r /usr/share/flam3/flam3-palettes.xml ]; then
  "$FB" flame $N --file ok.flame --flame lib --size 32x32 -o lib.exr --quiet
  check "palette=\"7\" reads flam3's palette library" test $? -eq 0 -a -s lib.exr
fi
cli_finish
