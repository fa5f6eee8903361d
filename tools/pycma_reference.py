import warnings; warnings.filterwarnings("ignore")
import cma, numpy as np
def runs(name, f, x0fn, sig, popsize, target, seeds=21):
    succ=[]
    for s in range(1, seeds+1):
        opts = {'CMA_active': False, 'ftarget': target, 'seed': s, 'verbose': -9, 'maxfevals': 1e6}
        if popsize: opts['popsize'] = popsize
        es = cma.CMAEvolutionStrategy(x0fn(s), sig, opts)
        es.optimize(f)
        if es.result.fbest <= target: succ.append(es.result.evaluations)
    succ.sort()
    if succ:
        print(f"{name}: {len(succ)}/{seeds} succ, min {succ[0]} median {succ[len(succ)//2]} mean {np.mean(succ):.0f} max {succ[-1]}")
    else:
        print(f"{name}: 0/{seeds}")
runs("sphere", cma.ff.sphere, lambda s: 10*[1.0], 1.0, None, 1e-10)
runs("rosen", cma.ff.rosen, lambda s: 10*[0.0], 0.5, None, 1e-10)
for lam in (100, 200, 400):
    runs(f"rastrigin lam {lam}", cma.ff.rastrigin, lambda s: np.random.default_rng(s).uniform(1,5,10), 2.0, lam, 1e-8)
