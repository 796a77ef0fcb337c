# Reference predictions of R gstat's idw() for errfield's scattered-IDW cross-check
# (tests/peers/gstat_idw_test.cpp). Usage:
#   Rscript gstat_idw.R samples.csv targets.csv idp nmax out.csv
# samples.csv: columns x, y, z, v; targets.csv: columns x, y, z; nmax "Inf" for all samples.
# Writes one column 'pred' with 17 significant digits. Exits with status 77 if gstat is missing.
args <- commandArgs(trailingOnly = TRUE)
if (length(args) != 5) stop("usage: gstat_idw.R samples.csv targets.csv idp nmax out.csv")
if (!suppressPackageStartupMessages(requireNamespace("gstat", quietly = TRUE))) quit(status = 77)
samples <- read.csv(args[1])
targets <- read.csv(args[2])
idp <- as.numeric(args[3])
nmax <- as.numeric(args[4])
r <- gstat::idw(v ~ 1, locations = ~ x + y + z, data = samples, newdata = targets,
                idp = idp, nmax = nmax, debug.level = 0)
write.csv(data.frame(pred = sprintf("%.17g", r$var1.pred)), args[5], row.names = FALSE, quote = FALSE)
