#!/usr/bin/env python3
"""Compare errfield with R gstat on gstat's `jura` data (Swiss Jura topsoil, 259 prediction and 100
validation locations), a data set the tests do not use: cross-variograms, fit.lmc, ordinary
cokriging (global and nmax = 20), kriging with external drift, the residual variogram and block
kriging. Prints the largest relative difference of each. Needs Rscript with gstat and sp.

Usage: gstat_jura_check.py ERRFIELD [--keep DIR]
"""
import argparse
import csv
import os
import subprocess
import sys
import tempfile

import numpy as np

R_SCRIPT = r"""
suppressMessages({library(gstat); library(sp)})
data(jura)
d <- jura.pred; d$lcd <- log(d$Cd); d$lni <- log(d$Ni); d$lzn <- log(d$Zn)
v <- jura.val; v$lni <- log(v$Ni)
write.csv(d[, c("Xloc","Yloc","lcd","lni","lzn")], "samples.csv", row.names = FALSE)
write.csv(v[, c("Xloc","Yloc","lni")], "targets.csv", row.names = FALSE)
coordinates(d) <- ~Xloc+Yloc; coordinates(v) <- ~Xloc+Yloc
lmc <- function(nmax) {
  g <- gstat(NULL, "lcd", lcd~1, d, nmax = nmax)
  g <- gstat(g, "lni", lni~1, d, nmax = nmax)
  g <- gstat(g, "lzn", lzn~1, d, nmax = nmax)
  vg <- variogram(g)
  list(vg = vg, fit = fit.lmc(vg, g, vgm(1, "Sph", 1, 1)))
}
a <- lmc(Inf)
write.csv(as.data.frame(a$vg)[, c("np","dist","gamma","id")], "gstat_cross.csv", row.names = FALSE)
s <- do.call(rbind, lapply(names(a$fit$model), function(id) data.frame(id = id, kind = as.character(a$fit$model[[id]]$model), psill = a$fit$model[[id]]$psill)))
write.csv(s, "gstat_lmc.csv", row.names = FALSE)
write.csv(as.data.frame(predict(a$fit, v)), "gstat_cok.csv", row.names = FALSE)
write.csv(as.data.frame(predict(lmc(20)$fit, v)), "gstat_cok20.csv", row.names = FALSE)
m <- vgm(0.3, "Sph", 1.2, 0.2)
write.csv(as.data.frame(krige(lcd ~ lni, d, v, model = m, debug.level = 0)), "gstat_ed.csv", row.names = FALSE)
write.csv(as.data.frame(variogram(lcd ~ lni, d))[, c("np","dist","gamma")], "gstat_rv.csv", row.names = FALSE)
write.csv(as.data.frame(krige(lcd ~ 1, d, v, model = m, block = c(0.4, 0.4), debug.level = 0)), "gstat_block.csv", row.names = FALSE)
"""


def read(path):
    with open(path) as f:
        rows = list(csv.reader(line for line in f if not line.startswith("#")))
    out = {}
    for i, name in enumerate(rows[0]):
        col = [r[i] for r in rows[1:]]
        try:
            out[name] = np.array([float(x) if x else np.nan for x in col])
        except ValueError:
            out[name] = np.array(col)
    return out


def worst(a, b):
    return float(np.max(np.abs(a - b) / np.maximum(np.abs(a), 1e-300)))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("errfield")
    ap.add_argument("--keep", help="work in this directory and keep the files")
    a = ap.parse_args()
    errfield = os.path.abspath(a.errfield)
    work = a.keep or tempfile.mkdtemp(prefix="errfield_jura_")
    os.makedirs(work, exist_ok=True)
    os.chdir(work)
    open("jura.R", "w").write(R_SCRIPT)
    subprocess.run(["Rscript", "jura.R"], check=True, capture_output=True)

    def ef(*args):
        subprocess.run([errfield, *args], check=True, capture_output=True)

    xy, vals = ["--coords", "Xloc,Yloc"], ["--value", "lcd,lni,lzn"]
    ef("variogram", "--input", "samples.csv", *xy, *vals, "--cross", "--out", "cross.csv")
    ef("fit-variogram", "--lmc", "--lmc-method", "gstat", "--input", "cross.csv", *vals, "--model", "nug(0)+sph(1,1)",
       "--out", "lmc.json")
    common = ["--samples", "samples.csv", "--targets", "targets.csv", *xy]
    ef("interpolate", "--method", "kriging", "--model", "lmc.json", *common, *vals, "--out", "cok.csv")
    ef("interpolate", "--method", "kriging", "--model", "lmc.json", *common, *vals, "--backend", "local",
       "--neighbors", "20", "--out", "cok20.csv")
    model = "sph(sill=0.3,range=1.2)+nug(0.2)"
    ef("interpolate", "--method", "kriging", "--model", model, *common, "--value", "lcd", "--covariates", "lni", "--out", "ed.csv")
    ef("variogram", "--input", "samples.csv", *xy, "--value", "lcd", "--covariates", "lni", "--out", "rv.csv")
    ef("interpolate", "--method", "kriging", "--model", model, *common, "--value", "lcd", "--block", "0.4,0.4", "--out", "block.csv")

    names = ["lcd", "lni", "lzn"]
    pairs = [(i, j) for i in range(3) for j in range(i, 3)]
    g, e = read("gstat_cross.csv"), read("cross.csv")
    nonempty = e["pairs"] > 0
    cross = 0.0
    for i, j in pairs:
        gid = names[i] if i == j else f"{names[i]}.{names[j]}"
        col = f"gamma_{names[i]}" if i == j else f"gamma_{names[i]}_{names[j]}"
        cross = max(cross, worst(g["gamma"][g["id"] == gid], e[col][nonempty]))
    print(f"cross-variograms (6 x 15 bins):            {cross:.1e}")
    import json
    fit = json.load(open("lmc.json"))["structures"]
    gl = read("gstat_lmc.csv")
    lmc = 0.0
    for i, j in pairs:
        gid = names[i] if i == j else f"{names[i]}.{names[j]}"
        ps = gl["psill"][gl["id"] == gid]  # nug, sph
        lmc = max(lmc, worst(ps, np.array([fit[0]["sills"][i][j], fit[1]["sills"][i][j]])))
    print(f"fit.lmc sills (gstat method, nj/h^2):       {lmc:.1e}")
    columns = [(f"{n}.pred", f"pred_{n}") for n in names] + [(f"{n}.var", f"var_{n}") for n in names] + \
              [(f"cov.{names[i]}.{names[j]}", f"cov_{names[i]}_{names[j]}") for i, j in pairs if i != j]
    g, e = read("gstat_cok.csv"), read("cok.csv")
    print(f"cokriging, global (pred, var, cov):        {max(worst(g[a], e[b]) for a, b in columns):.1e}")
    g, e, s = read("gstat_cok20.csv"), read("cok20.csv"), read("samples.csv")
    # Targets whose 20th and 21st nearest samples are equally far: gstat and errfield may keep different ones.
    keep = []
    for t in range(len(g["Xloc"])):
        dist = np.sort(np.hypot(s["Xloc"] - g["Xloc"][t], s["Yloc"] - g["Yloc"][t]))
        keep.append(abs(dist[19] - dist[20]) > 1e-9 * dist[20])
    keep = np.array(keep)
    local = max(worst(g[a][keep], e[b][keep]) for a, b in columns)
    print(f"cokriging, nmax = 20 ({keep.sum()} of {len(keep)} targets without a tie): {local:.1e}")
    g, e = read("gstat_ed.csv"), read("ed.csv")
    print(f"external drift lcd ~ lni (pred, var):      {max(worst(g['var1.pred'], e['pred']), worst(g['var1.var'], e['var'])):.1e}")
    g, e = read("gstat_rv.csv"), read("rv.csv")
    print(f"residual variogram:                         {worst(g['gamma'], e['gamma'][e['pairs'] > 0]):.1e}")
    g, e = read("gstat_block.csv"), read("block.csv")
    print(f"block kriging 0.4 x 0.4 (pred, var):        {max(worst(g['var1.pred'], e['pred']), worst(g['var1.var'], e['var'])):.1e}"
          "  (gstat keeps its block weights in float32: docs/kriging.md)")
    if not a.keep:
        print(f"(work files in {work})")


if __name__ == "__main__":
    main()
