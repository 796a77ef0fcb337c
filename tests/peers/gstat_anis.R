# Peer of errfield's rotated anisotropy: gstat's krige with vgm(..., anis=) on the given samples.
# Usage: Rscript gstat_anis.R SAMPLES.csv TARGETS.csv DIMS ANIS OUT.csv [NMAX]
#   DIMS 2 or 3 (coordinates x,y[,z]; value v), ANIS comma-separated (angle,ratio or p,q,r,s,t).
# Model: Exp(psill 1, range 40) + Nug(0.01), ordinary kriging; writes pred to OUT.csv.
suppressPackageStartupMessages({library(gstat); library(sp)})
a <- commandArgs(trailingOnly = TRUE)
d <- read.csv(a[1]); t <- read.csv(a[2])
f <- if (a[3] == "3") ~x + y + z else ~x + y
coordinates(d) <- f; coordinates(t) <- f
anis <- as.numeric(strsplit(a[4], ",")[[1]])
nmax <- if (length(a) >= 6) as.numeric(a[6]) else Inf  # local kriging: gstat's nearest by Euclidean distance
k <- krige(v ~ 1, d, t, model = vgm(1, "Exp", 40, 0.01, anis = anis), nmax = nmax, debug.level = 0)
write.csv(data.frame(pred = k$var1.pred), a[5], row.names = FALSE)
