# Reference predictions of R gstat's idw() for errfield's scattered-IDW cross-check
# (tests/peers/gstat_idw_test.cpp). Usage:
#   Rscript gstat_idw.R samples.csv targets.csv out.csv IDP:NMAX [IDP:NMAX ...]
# samples.csv: columns x, y, z, v; targets.csv: columns x, y, z; NMAX "Inf" for all samples.
# Writes one column per case, pred1, pred2, ..., with 17 significant digits.
# Exits with status 77 if gstat is not installed.
args <- commandArgs(trailingOnly = TRUE)
if (length(args) < 4) stop("usage: gstat_idw.R samples.csv targets.csv out.csv IDP:NMAX [IDP:NMAX ...]")
if (!suppressPackageStartupMessages(requireNamespace("gstat", quietly = TRUE))) quit(status = 77)
samples <- read.csv(args[1])
targets <- read.csv(args[2])
out <- data.frame(row.names = seq_len(nrow(targets)))
cases <- args[-(1:3)]
for (i in seq_along(cases)) {
  parts <- strsplit(cases[i], ":", fixed = TRUE)[[1]]
  r <- gstat::idw(v ~ 1, locations = ~ x + y + z, data = samples, newdata = targets,
                  idp = as.numeric(parts[1]), nmax = as.numeric(parts[2]), debug.level = 0)
  out[[paste0("pred", i)]] <- sprintf("%.17g", r$var1.pred)
}
write.csv(out, args[3], row.names = FALSE, quote = FALSE)
