#include "rbcd/cpu/cpu_collision.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>

#include <btBulletCollisionCommon.h>
#include <BulletCollision/Gimpact/btGImpactCollisionAlgorithm.h>
#include <BulletCollision/Gimpact/btGImpactShape.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkEpaPenetrationDepthSolver.h>
#include <BulletCollision/NarrowPhaseCollision/btGjkPairDetector.h>
#include <BulletCollision/NarrowPhaseCollision/btVoronoiSimplexSolver.h>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <fcl/geometry/bvh/BVH_model.h>
#include <fcl/math/bv/OBBRSS.h>
#include <fcl/narrowphase/collision.h>
#include <fcl/narrowphase/collision_object.h>

namespace rbcd::cpucd {

namespace {

using Clock = std::chrono::steady_clock;
double us_since(Clock::time_point t0) { return std::chrono::duration<double, std::micro>(Clock::now() - t0).count(); }

double median(std::vector<double> v) {
    std::sort(v.begin(), v.end());
    const std::size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Model matrix = [R * diag(s) | t] (the scene's scale-rotate-translate; a
// mirror shows as a negative s.x). Rigid part for Bullet/FCL, scale apart.
struct Decomposed {
    Eigen::Matrix3d rot;
    Eigen::Vector3d scale, trans;
};
Decomposed decompose(const Eigen::Matrix4d& m) {
    Decomposed d;
    const Eigen::Matrix3d l = m.block<3, 3>(0, 0);
    for (int k = 0; k < 3; ++k) {
        d.scale[k] = l.col(k).norm();
        d.rot.col(k) = l.col(k) / d.scale[k];
    }
    if (d.rot.determinant() < 0) {
        d.scale[0] = -d.scale[0];
        d.rot.col(0) = -d.rot.col(0);
    }
    d.trans = m.block<3, 1>(0, 3);
    return d;
}

btTransform to_bt(const Decomposed& d) {
    btMatrix3x3 b(btScalar(d.rot(0, 0)), btScalar(d.rot(0, 1)), btScalar(d.rot(0, 2)), btScalar(d.rot(1, 0)),
                  btScalar(d.rot(1, 1)), btScalar(d.rot(1, 2)), btScalar(d.rot(2, 0)), btScalar(d.rot(2, 1)),
                  btScalar(d.rot(2, 2)));
    return btTransform(b, btVector3(btScalar(d.trans.x()), btScalar(d.trans.y()), btScalar(d.trans.z())));
}

struct GjkResult : btDiscreteCollisionDetectorInterface::Result {
    bool has = false;
    btScalar dist = 0;
    void setShapeIdentifiersA(int, int) override {}
    void setShapeIdentifiersB(int, int) override {}
    void addContactPoint(const btVector3&, const btVector3&, btScalar depth) override {
        has = true;
        dist = depth;
    }
};

using Bvh = fcl::BVHModel<fcl::OBBRSSd>;

// Parts of one object never collide (what a game does with a ragdoll's
// limbs); the collision object's user index is its part.
struct SameObjectFilter : btOverlapFilterCallback {
    const CdInput* in = nullptr;
    bool needBroadphaseCollision(btBroadphaseProxy* a, btBroadphaseProxy* b) const override {
        const auto* oa = static_cast<const btCollisionObject*>(a->m_clientObject);
        const auto* ob = static_cast<const btCollisionObject*>(b->m_clientObject);
        return in->parts[std::size_t(oa->getUserIndex())].id != in->parts[std::size_t(ob->getUserIndex())].id;
    }
};

// A btCollisionWorld as a game sets one up. Members in this order: the world's
// destructor removes the objects' proxies, so the objects, the broad phase
// and the filter outlive it.
struct World {
    SameObjectFilter filter;
    std::vector<std::unique_ptr<btCollisionObject>> objs;
    btDefaultCollisionConfiguration config;
    btCollisionDispatcher dispatcher{&config};
    btDbvtBroadphase broadphase;
    btCollisionWorld world{&dispatcher, &broadphase, &config};
};

} // namespace

struct CpuDetector::Impl {
    const CdInput& in;
    btDefaultCollisionConfiguration config;
    btCollisionDispatcher dispatcher{&config};
    btDbvtBroadphase broadphase;
    btVoronoiSimplexSolver simplex;
    btGjkEpaPenetrationDepthSolver epa;

    DetectorOptions opt;

    struct PartState {
        std::unique_ptr<btConvexHullShape> hull;
        // (e)'s shape for a concave part: GImpact over the mesh (single precision, as Bullet stores it).
        bool convex = true;
        std::vector<btScalar> gverts;
        std::vector<int> gidx;
        std::unique_ptr<btTriangleIndexVertexArray> gmesh;
        std::unique_ptr<btGImpactMeshShape> gimpact;
        btVector3 g_scale{1, 1, 1};   // the GImpact shape's, rescaled by the world steps only
        btBroadphaseProxy* proxy = nullptr;
        btVector3 bt_scale{1, 1, 1};
        btTransform tr;
        // FCL model in scaled object space, rebuilt when the scale changes.
        std::shared_ptr<Bvh> bvh;
        Eigen::Vector3d bvh_scale{0, 0, 0};
        bool closed = false;
    };
    std::vector<PartState> ps;
    // (d), (e). After the parts: a world's objects point at the parts'
    // shapes, so the worlds go first.
    World wbroad, wfull;

    Impl(const CdInput& input, DetectorOptions o) : in(input), opt(o) {
        ps.resize(in.parts.size());
        std::map<const PartMesh*, bool> closed, convex;
        for (std::size_t i = 0; i < in.parts.size(); ++i) {
            const PartMesh& m = *in.parts[i].mesh;
            auto hull = std::make_unique<btConvexHullShape>();
            for (const auto& v : m.verts)
                hull->addPoint(btVector3(btScalar(v.x()), btScalar(v.y()), btScalar(v.z())), false);
            hull->recalcLocalAabb();
            hull->optimizeConvexHull();   // keeps the hull's vertices only: exact, faster support mapping
            hull->setMargin(0);           // margins zeroed: the shapes are the hulls themselves
            hull->recalcLocalAabb();
            ps[i].hull = std::move(hull);
            auto it = closed.find(&m);
            if (it == closed.end()) it = closed.emplace(&m, is_closed(m)).first;
            ps[i].closed = it->second;
            auto cv = convex.find(&m);
            if (cv == convex.end()) cv = convex.emplace(&m, is_convex(m)).first;
            ps[i].convex = cv->second;
            if (!ps[i].convex) {
                PartState& p = ps[i];
                p.gverts.reserve(3 * m.verts.size());
                for (const auto& v : m.verts)
                    for (int k = 0; k < 3; ++k) p.gverts.push_back(btScalar(v[k]));
                p.gidx.reserve(3 * m.tris.size());
                for (const auto& t : m.tris)
                    for (int k = 0; k < 3; ++k) p.gidx.push_back(int(t[k]));
                p.gmesh = std::make_unique<btTriangleIndexVertexArray>(int(m.tris.size()), p.gidx.data(), 3 * int(sizeof(int)),
                                                                       int(m.verts.size()), p.gverts.data(),
                                                                       3 * int(sizeof(btScalar)));
                p.gimpact = std::make_unique<btGImpactMeshShape>(p.gmesh.get());
                p.gimpact->setMargin(0);
                p.gimpact->updateBound();
            }
        }
        // Proxies at frame 0.
        for (std::size_t i = 0; i < ps.size(); ++i) {
            set_pose(i, in.model.empty() ? Eigen::Matrix4d::Identity() : in.model[0][i]);
            btVector3 lo, hi;
            ps[i].hull->getAabb(ps[i].tr, lo, hi);
            ps[i].proxy = broadphase.createProxy(lo, hi, CONVEX_HULL_SHAPE_PROXYTYPE, &ps[i], 1, -1, &dispatcher);
        }
        broadphase.calculateOverlappingPairs(&dispatcher);
        // The worlds at frame 0, their pairs found: loading, as the proxies above.
        btGImpactCollisionAlgorithm::registerAlgorithm(&wfull.dispatcher);
        for (World* w : {&wbroad, &wfull}) {
            w->filter.in = &in;
            w->world.getPairCache()->setOverlapFilterCallback(&w->filter);
            for (std::size_t i = 0; i < ps.size(); ++i) {
                auto o = std::make_unique<btCollisionObject>();
                o->setCollisionShape(shape(i));
                o->setWorldTransform(ps[i].tr);
                o->setUserIndex(int(i));
                w->world.addCollisionObject(o.get());
                w->objs.push_back(std::move(o));
            }
        }
        if (!in.model.empty()) {
            world_step(wbroad, 0, false);
            world_step(wfull, 0, true);
        }
    }

    ~Impl() {
        for (auto& p : ps)
            if (p.proxy) broadphase.destroyProxy(p.proxy, &dispatcher);
    }

    btCollisionShape* shape(std::size_t i) {
        return ps[i].convex ? static_cast<btCollisionShape*>(ps[i].hull.get()) : ps[i].gimpact.get();
    }

    // Empty broad phase and worlds (fresh inputs): the next broad() or
    // world_step() inserts every part again.
    void clear_broad() {
        for (auto& p : ps)
            if (p.proxy) {
                broadphase.destroyProxy(p.proxy, &dispatcher);
                p.proxy = nullptr;
            }
    }
    static void clear_world(World& w) {
        for (auto& o : w.objs)
            if (o->getBroadphaseHandle()) w.world.removeCollisionObject(o.get());
    }

    // (d) (narrow = false: the world's AABBs and overlapping pairs, what
    // performDiscreteCollisionDetection does before dispatching) or (e).
    void world_step(World& w, std::uint64_t f, bool narrow) {
        for (std::size_t i = 0; i < ps.size(); ++i) {
            set_pose(i, in.model[f][i]);
            PartState& p = ps[i];
            // A scaled concave shape refits its tree: the world's work, not the bare queries'.
            if (p.gimpact && p.g_scale != p.bt_scale) {
                p.gimpact->setLocalScaling(p.bt_scale);
                p.gimpact->updateBound();
                p.g_scale = p.bt_scale;
            }
            w.objs[i]->setWorldTransform(p.tr);
            if (!w.objs[i]->getBroadphaseHandle()) w.world.addCollisionObject(w.objs[i].get());
        }
        if (narrow) {
            w.world.performDiscreteCollisionDetection();
        } else {
            w.world.updateAabbs();
            w.world.computeOverlappingPairs();
        }
    }

    void set_pose(std::size_t i, const Eigen::Matrix4d& m) {
        const Decomposed d = decompose(m);
        PartState& p = ps[i];
        // A rotating object's scale, recovered from its matrix, wobbles in
        // the last bits of a double; Bullet keeps it in floats. Rescaling
        // only when the float changes keeps a constant scale constant, as a
        // game sets it once (rescaling recomputes the hull's box and refits
        // a GImpact tree), and changes no result.
        const btVector3 s(btScalar(d.scale.x()), btScalar(d.scale.y()), btScalar(d.scale.z()));
        if (s != p.bt_scale) {
            p.hull->setLocalScaling(s);
            p.bt_scale = s;
        }
        p.tr = to_bt(d);
    }

    // (a): AABBs updated, broadphase pairs, filtered by exact AABB overlap and distinct ids.
    void broad(std::uint64_t f, std::vector<std::pair<std::size_t, std::size_t>>& out) {
        for (std::size_t i = 0; i < ps.size(); ++i) {
            set_pose(i, in.model[f][i]);
            btVector3 lo, hi;
            ps[i].hull->getAabb(ps[i].tr, lo, hi);
            if (ps[i].proxy)
                broadphase.setAabb(ps[i].proxy, lo, hi, &dispatcher);
            else
                ps[i].proxy = broadphase.createProxy(lo, hi, CONVEX_HULL_SHAPE_PROXYTYPE, &ps[i], 1, -1, &dispatcher);
        }
        broadphase.calculateOverlappingPairs(&dispatcher);
        out.clear();
        const btBroadphasePairArray& arr = broadphase.getOverlappingPairCache()->getOverlappingPairArray();
        for (int k = 0; k < arr.size(); ++k) {
            const btBroadphaseProxy* p0 = arr[k].m_pProxy0;
            const btBroadphaseProxy* p1 = arr[k].m_pProxy1;
            // The tree's leaves are enlarged; the pair counts only when the true AABBs overlap.
            if (!TestAabbAgainstAabb2(p0->m_aabbMin, p0->m_aabbMax, p1->m_aabbMin, p1->m_aabbMax)) continue;
            const std::size_t i = std::size_t(static_cast<PartState*>(p0->m_clientObject) - ps.data());
            const std::size_t j = std::size_t(static_cast<PartState*>(p1->m_clientObject) - ps.data());
            if (in.parts[i].id == in.parts[j].id) continue;
            out.emplace_back(std::min(i, j), std::max(i, j));
        }
    }

    // (b)'s narrow phase on one pair: 1 contact, 0 apart, 2 no answer (counted as contact).
    int gjk(std::size_t i, std::size_t j) {
        btGjkPairDetector det(ps[i].hull.get(), ps[j].hull.get(), &simplex, &epa);
        btGjkPairDetector::ClosestPointInput ci;
        ci.m_transformA = ps[i].tr;
        ci.m_transformB = ps[j].tr;
        GjkResult r;
        det.getClosestPoints(ci, r, nullptr);
        if (!r.has) return 2;
        return r.dist <= btScalar(0) ? 1 : 0;
    }

    const Bvh& bvh(std::size_t i, const Eigen::Vector3d& scale) {
        PartState& p = ps[i];
        if (!p.bvh || p.bvh_scale != scale) {
            const PartMesh& m = *in.parts[i].mesh;
            std::vector<Eigen::Vector3d> v(m.verts.size());
            for (std::size_t k = 0; k < v.size(); ++k) v[k] = m.verts[k].cwiseProduct(scale);
            std::vector<fcl::Triangle> t;
            t.reserve(m.tris.size());
            for (const auto& tr : m.tris) t.emplace_back(tr[0], tr[1], tr[2]);
            auto model = std::make_shared<Bvh>();
            model->beginModel(int(t.size()), int(v.size()));
            model->addSubModel(v, t);
            model->endModel();
            p.bvh = std::move(model);
            p.bvh_scale = scale;
        }
        return *p.bvh;
    }

    using Pairs = std::map<std::pair<std::uint32_t, std::uint32_t>, PairResult>;
    using Candidates = std::vector<std::pair<std::size_t, std::size_t>>;
    // The entry of parts i and j's objects, made on first use.
    PairResult& pair_of(Pairs& pairs, std::size_t i, std::size_t j) const {
        std::uint32_t a = in.parts[i].id, b = in.parts[j].id;
        if (a > b) std::swap(a, b);
        PairResult& p = pairs[{a, b}];
        p.a = a;
        p.b = b;
        p.open = p.open || !ps[i].closed || !ps[j].closed;
        return p;
    }
    void timed_phases(std::uint64_t f, unsigned repeats, SectionCounter* counter, FrameResult& fr, Candidates& cand,
                      std::vector<int>& gres);
    void note_phase_pairs(Pairs& pairs, FrameResult& fr, const Candidates& cand, const std::vector<int>& gres);
    // FCL models, at this frame's scale, of the parts in `cand` (the pairs
    // the exact phase tests): building them is loading, not detection, and
    // only the parts the exact phase meets need one.
    void build_bvhs(std::uint64_t f, const Candidates& cand) {
        for (const auto& [i, j] : cand)
            for (const std::size_t k : {i, j}) bvh(k, decompose(in.model[f][k]).scale);
    }
    void exact_phase(std::uint64_t f, const Candidates& cand, Pairs& pairs);
};

CpuDetector::CpuDetector(const CdInput& in, DetectorOptions opt) : impl_(std::make_unique<Impl>(in, opt)) {}

std::size_t CpuDetector::concave_parts() const {
    std::size_t n = 0;
    for (const auto& p : impl_->ps) n += !p.convex;
    return n;
}
CpuDetector::~CpuDetector() = default;

// ---- (a), (b), (d), (e), timed, each repeat starting from frame f-1's
// state; the first repeat also counted when a counter is given.
void CpuDetector::Impl::timed_phases(std::uint64_t f, unsigned repeats, SectionCounter* counter, FrameResult& fr,
                                     Candidates& cand, std::vector<int>& gres) {
    std::vector<double> tb, tg, twb, tw;
    const std::uint64_t prev = f ? f - 1 : 0;
    for (unsigned r = 0; r < std::max(1u, repeats); ++r) {
        SectionCounter* c = r == 0 ? counter : nullptr;
        const auto measure = [&](Section sec, std::vector<double>& times, auto&& work) {
            const auto t0 = Clock::now();
            if (c) c->start();
            work();
            if (c) fr.instr[std::size_t(sec)] = c->stop(sec);
            times.push_back(us_since(t0));
        };
        // Unmeasured: back to the previous frame, or (fresh) to nothing.
        const auto reset_broad = [&] {
            if (opt.fresh) clear_broad();
            else broad(prev, cand);
        };
        const auto reset_world = [&](World& w, bool narrow) {
            if (opt.fresh) clear_world(w);
            else world_step(w, prev, narrow);
        };
        reset_broad();
        measure(Section::broad, tb, [&] { broad(f, cand); });

        reset_broad();
        measure(Section::gjk, tg, [&] {
            broad(f, cand);
            gres.assign(cand.size(), 0);
            for (std::size_t k = 0; k < cand.size(); ++k) gres[k] = gjk(cand[k].first, cand[k].second);
        });

        reset_world(wbroad, false);
        measure(Section::world_broad, twb, [&] { world_step(wbroad, f, false); });
        reset_world(wfull, true);
        measure(Section::world, tw, [&] { world_step(wfull, f, true); });
    }
    fr.t.broad_us = median(tb);
    fr.t.gjk_us = median(tg);
    fr.t.world_broad_us = median(twb);
    fr.t.world_us = median(tw);
}

// The pairs of the broad phase and GJK, and of the two worlds.
void CpuDetector::Impl::note_phase_pairs(Pairs& pairs, FrameResult& fr, const Candidates& cand,
                                         const std::vector<int>& gres) {
    for (std::size_t k = 0; k < cand.size(); ++k) {
        PairResult& p = pair_of(pairs, cand[k].first, cand[k].second);
        p.aabb = true;
        if (gres[k]) p.gjk = true;
        if (gres[k] == 2) ++fr.t.gjk_no_result;
    }
    // (d)'s pairs: the world's pair cache, kept when the shapes' own AABBs
    // overlap (the world's proxies are enlarged by the contact-breaking
    // threshold, the tree's leaves further).
    {
        const btBroadphasePairArray& arr = wbroad.world.getPairCache()->getOverlappingPairArray();
        for (int k = 0; k < arr.size(); ++k) {
            const auto* o0 = static_cast<const btCollisionObject*>(arr[k].m_pProxy0->m_clientObject);
            const auto* o1 = static_cast<const btCollisionObject*>(arr[k].m_pProxy1->m_clientObject);
            btVector3 lo0, hi0, lo1, hi1;
            o0->getCollisionShape()->getAabb(o0->getWorldTransform(), lo0, hi0);
            o1->getCollisionShape()->getAabb(o1->getWorldTransform(), lo1, hi1);
            if (!TestAabbAgainstAabb2(lo0, hi0, lo1, hi1)) continue;
            pair_of(pairs, std::size_t(o0->getUserIndex()), std::size_t(o1->getUserIndex())).world_aabb = true;
        }
    }
    // (e)'s: a manifold holding a point at distance <= 0 (the manifolds also
    // keep points within the contact-breaking threshold, not touching).
    for (int k = 0; k < wfull.dispatcher.getNumManifolds(); ++k) {
        const btPersistentManifold* m = wfull.dispatcher.getManifoldByIndexInternal(k);
        bool touching = false;
        for (int q = 0; q < m->getNumContacts(); ++q) touching = touching || m->getContactPoint(q).getDistance() <= 0;
        if (touching)
            pair_of(pairs, std::size_t(m->getBody0()->getUserIndex()), std::size_t(m->getBody1()->getUserIndex())).world =
                true;
    }
}

// ---- (c) exact, over `cand`: the pairs whose exact (double) world AABBs
// overlap (overlapping_aabb_pairs), their BVHs built (build_bvhs).
void CpuDetector::Impl::exact_phase(std::uint64_t f, const Candidates& cand, Pairs& pairs) {
    const std::size_t n = in.parts.size();
    std::vector<Decomposed> dec(n);
    for (std::size_t i = 0; i < n; ++i) dec[i] = decompose(in.model[f][i]);
    auto world_vert = [&](std::size_t i, std::size_t k) {
        const Eigen::Matrix4d& m = in.model[f][i];
        return Eigen::Vector3d(m.block<3, 3>(0, 0) * in.parts[i].mesh->verts[k] + m.block<3, 1>(0, 3));
    };
    auto inner_on_screen = [&](std::size_t i) {
        for (std::size_t k = 0; k < in.parts[i].mesh->verts.size(); ++k)
            if (in_view(in.view_proj, world_vert(i, k))) return true;
        return false;
    };
    for (const auto& [i, j] : cand) {
        const Bvh& bi = bvh(i, dec[i].scale);
        const Bvh& bj = bvh(j, dec[j].scale);
        fcl::Transform3d ti = fcl::Transform3d::Identity(), tj = fcl::Transform3d::Identity();
        ti.linear() = dec[i].rot;
        ti.translation() = dec[i].trans;
        tj.linear() = dec[j].rot;
        tj.translation() = dec[j].trans;
        fcl::CollisionRequestd req(1, false);
        fcl::CollisionResultd res;
        fcl::collide(&bi, ti, &bj, tj, req, res);
        if (res.isCollision()) {
            PairResult& p = pair_of(pairs, i, j);
            p.exact = true;
            if (in.has_view) {
                fcl::CollisionRequestd creq(64, true);
                fcl::CollisionResultd cres;
                fcl::collide(&bi, ti, &bj, tj, creq, cres);
                std::vector<fcl::Contactd> cs;
                cres.getContacts(cs);
                p.contacts += unsigned(cs.size());
                for (const auto& c : cs)
                    if (in_view(in.view_proj, c.pos)) p.on_screen = true;
            }
            continue;
        }
        // Containment: FCL misses a surface wholly inside another.
        for (int side = 0; side < 2; ++side) {
            const std::size_t inner = side ? j : i, outer = side ? i : j;
            if (!ps[outer].closed) continue;   // parity means nothing for an open mesh
            const Eigen::Matrix4d inv = in.model[f][outer].inverse();
            const Eigen::Vector3d pw = world_vert(inner, 0);
            const Eigen::Vector3d pl = (inv * pw.homogeneous()).head<3>();
            if (point_in_mesh(*in.parts[outer].mesh, pl)) {
                PairResult& p = pair_of(pairs, i, j);
                p.exact = true;
                p.contained = true;
                if (in.has_view && inner_on_screen(inner)) p.on_screen = true;
                break;
            }
        }
    }
}

FrameResult CpuDetector::run_frame(std::uint64_t f, unsigned repeats, SectionCounter* counter) {
    Impl& s = *impl_;
    FrameResult fr;
    fr.frame = f;
    Impl::Pairs pairs;
    Impl::Candidates cand;
    std::vector<int> gres;
    s.timed_phases(f, repeats, counter, fr, cand, gres);
    s.note_phase_pairs(pairs, fr, cand, gres);
    if (s.opt.exact) {
        const Impl::Candidates exact_cand = overlapping_aabb_pairs(s.in, f, UINT64_MAX).pairs;
        s.build_bvhs(f, exact_cand);
        const auto t0 = Clock::now();
        s.exact_phase(f, exact_cand, pairs);
        fr.t.exact_us = us_since(t0);
    }
    // A pair exact for one part pair and merely contained for another is an intersection.
    for (auto& [k, p] : pairs) fr.pairs.push_back(p);
    return fr;
}

AabbPairs overlapping_aabb_pairs(const CdInput& in, std::uint64_t f, std::uint64_t limit) {
    const std::size_t n = in.parts.size();
    std::vector<Eigen::Vector3d> lo(n), hi(n);
    Eigen::Vector3d sum = Eigen::Vector3d::Zero(), sum2 = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < n; ++i) {
        const Eigen::Matrix4d& m = in.model[f][i];
        lo[i] = Eigen::Vector3d::Constant(HUGE_VAL);
        hi[i] = Eigen::Vector3d::Constant(-HUGE_VAL);
        for (const auto& v : in.parts[i].mesh->verts) {
            const Eigen::Vector3d w = m.block<3, 3>(0, 0) * v + m.block<3, 1>(0, 3);
            lo[i] = lo[i].cwiseMin(w);
            hi[i] = hi[i].cwiseMax(w);
        }
        const Eigen::Vector3d c = 0.5 * (lo[i] + hi[i]);
        sum += c;
        sum2 += c.cwiseProduct(c);
    }
    int axis = 0;
    const Eigen::Vector3d spread = sum2 - sum.cwiseProduct(sum) / double(std::max<std::size_t>(n, 1));
    spread.maxCoeff(&axis);
    std::vector<std::size_t> order(n);
    for (std::size_t i = 0; i < n; ++i) order[i] = i;
    std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return lo[a][axis] < lo[b][axis]; });
    AabbPairs out;
    std::uint64_t candidates = 0;
    for (std::size_t a = 0; a < n; ++a) {
        const std::size_t i = order[a];
        for (std::size_t b = a + 1; b < n && lo[order[b]][axis] <= hi[i][axis]; ++b) {
            if (++candidates > limit) {
                out.over_limit = true;
                return out;
            }
            const std::size_t j = order[b];
            if (in.parts[i].id == in.parts[j].id) continue;
            if ((lo[i].array() > hi[j].array()).any() || (lo[j].array() > hi[i].array()).any()) continue;
            out.pairs.emplace_back(std::min(i, j), std::max(i, j));
        }
    }
    std::sort(out.pairs.begin(), out.pairs.end());
    return out;
}

bool is_convex(const PartMesh& m) {
    if (m.verts.empty()) return true;
    Eigen::Vector3d lo = m.verts[0], hi = m.verts[0];
    for (const auto& v : m.verts) {
        lo = lo.cwiseMin(v);
        hi = hi.cwiseMax(v);
    }
    // Tessellation and file precision leave vertices slightly off a flat
    // face; a millionth of the mesh's size is far below any concavity that
    // changes which objects touch.
    const double tol = 1e-6 * (hi - lo).norm();
    // Only the vertices that can be in front of a plane matter: those of the
    // hull. Bullet's optimizeConvexHull keeps exactly those.
    btConvexHullShape hull;
    for (const auto& v : m.verts) hull.addPoint(btVector3(btScalar(v.x()), btScalar(v.y()), btScalar(v.z())), false);
    hull.optimizeConvexHull();
    std::vector<Eigen::Vector3d> hv;
    hv.reserve(std::size_t(hull.getNumPoints()));
    for (int k = 0; k < hull.getNumPoints(); ++k) {
        const btVector3& p = hull.getUnscaledPoints()[k];
        hv.emplace_back(double(p.x()), double(p.y()), double(p.z()));
    }
    // The hull is single precision: a vertex off by its rounding is not a concavity.
    const double tol_f = tol + 1e-6 * std::max(lo.cwiseAbs().maxCoeff(), hi.cwiseAbs().maxCoeff());
    for (const auto& t : m.tris) {
        const Eigen::Vector3d& a = m.verts[t[0]];
        const Eigen::Vector3d n = (m.verts[t[1]] - a).cross(m.verts[t[2]] - a);
        const double len = n.norm();
        if (len == 0) continue;   // degenerate: no plane
        const Eigen::Vector3d u = n / len;
        for (const auto& v : hv)
            if (u.dot(v - a) > tol_f) return false;
    }
    return true;
}

bool point_in_mesh(const PartMesh& m, const Eigen::Vector3d& p) {
    // A direction no axis-aligned or diagonal feature of the built-in shapes
    // lies along, so that the ray rarely grazes an edge or a vertex.
    static const Eigen::Vector3d dir = Eigen::Vector3d(0.5377, 0.7117, 0.4512).normalized();
    unsigned crossings = 0;
    for (const auto& t : m.tris) {
        const Eigen::Vector3d& v0 = m.verts[t[0]];
        const Eigen::Vector3d e1 = m.verts[t[1]] - v0, e2 = m.verts[t[2]] - v0;
        const Eigen::Vector3d h = dir.cross(e2);
        const double a = e1.dot(h);
        if (std::abs(a) < 1e-14) continue;
        const double fi = 1.0 / a;
        const Eigen::Vector3d s = p - v0;
        const double u = fi * s.dot(h);
        if (u < 0.0 || u > 1.0) continue;
        const Eigen::Vector3d q = s.cross(e1);
        const double v = fi * dir.dot(q);
        if (v < 0.0 || u + v > 1.0) continue;
        if (fi * e2.dot(q) > 0.0) ++crossings;
    }
    return crossings % 2 == 1;
}

bool in_view(const Eigen::Matrix4d& vp, const Eigen::Vector3d& p) {
    const Eigen::Vector4d c = vp * p.homogeneous();
    return c.w() > 0 && std::abs(c.x()) <= c.w() && std::abs(c.y()) <= c.w() && std::abs(c.z()) <= c.w();
}

} // namespace rbcd::cpucd
