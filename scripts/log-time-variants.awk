# Rewrites a log (docs/log-format.md, Unix seconds in time_s) in the other forms the format allows,
# for the C example's comparison with host-sim (scripts/test-all.sh):
#   awk -v MODE=ms -f scripts/log-time-variants.awk LOG    time_ms, ';' separators, header names
#                                                          in capitals and with spaces
#   awk -v MODE=utc -f scripts/log-time-variants.awk LOG   time_utc (ISO 8601 to the microsecond),
#                                                          tab separators; every other row with an
#                                                          offset of +02:00 and a space for the T
function civil(z,   era, doe, yoe, y, doy, mp, d, m) {
    z += 719468; era = int(z / 146097); doe = z - era * 146097
    yoe = int((doe - int(doe / 1460) + int(doe / 36524) - int(doe / 146096)) / 365)
    y = yoe + era * 400; doy = doe - (365 * yoe + int(yoe / 4) - int(yoe / 100))
    mp = int((5 * doy + 2) / 153); d = doy - int((153 * mp + 2) / 5) + 1
    m = mp < 10 ? mp + 3 : mp - 9; y += (m <= 2)
    return sprintf("%04d-%02d-%02d", y, m, d)
}
function utc(t, offset_h,   sec, us, days, rem) {
    sec = int(t); us = int((t - sec) * 1e6 + 0.5); if (us >= 1000000) { sec++; us -= 1000000 }
    sec += offset_h * 3600; days = int(sec / 86400); rem = sec - days * 86400
    return sprintf("%s%s%02d:%02d:%02d.%06d%s", civil(days), offset_h ? " " : "T", int(rem / 3600),
        int(rem % 3600 / 60), rem % 60, us, offset_h ? sprintf("+%02d:00", offset_h) : "Z")
}
BEGIN { FS = "," }
NR == 1 {
    if (MODE == "ms") { print "TIME MS;Rotation Deg;PLATFORM_DEG;latitude deg;Heading_Deg;roll_deg;Pitch Deg"; next }
    print "time_utc\trotation_deg\tplatform_deg\tlatitude_deg\theading_deg\troll_deg\tpitch_deg"; next
}
{
    if (MODE == "ms") { $1 = sprintf("%.3f", $1 * 1000); OFS = ";" } else { $1 = utc($1, NR % 2 ? 0 : 2); OFS = "\t" }
    $1 = $1; print
}
