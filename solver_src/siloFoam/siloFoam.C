/*---------------------------------------------------------------------------*\
  foamsilo: granular silo discharge with OpenFOAM
-------------------------------------------------------------------------------
License
    This file is part of foamsilo, built against OpenFOAM (GPL-3.0-or-later).
    It is distributed under the GNU General Public License v3 or later.

Application
    siloFoam

Description
    interFoam-derived solver for the discharge of a dense granular material
    (phase 1, the VOF phase, with the mu(I) viscosity) through air (phase 2).

    What differs from interFoam (all else is included from
    $FOAM_SOLVERS/multiphase/interFoam and .../VoF):

    - Projection with the coefficient dt/rho (incremental pressure
      correction, the Basilisk/Gerris splitting) instead of 1/A: with mu(I)
      the viscous diagonal of A is 500-5000 times rho/dt and 1/A-projection
      lets the granular pressure swing sign from step to step (pEqn.H).
    - rho is bounded below by the lighter phase density in that coefficient,
      because MULES undershoots alpha slightly.
    - The momentum predictor is always solved (it provides U*).
    - The time step can be limited by the Courant number over the granular
      phase only (maxGranularCo), since the air above the free surface
      carries spurious fast velocities (granularCourantNo.H, setDeltaT.H).
    - Optional gas coupling (Zhou et al. 2019): a Darcy-Forchheimer pore
      pressure pf with the top condition of their eq. 16, whose gradient
      acts on the grains (createPorePressure.H, pfEqn.H; a start from rest
      carries the pore pressure's support, poreSupport.H), and optional
      quasi-2D wall friction (their eq. 14); a dry silo has neither.
    - A step whose outer iterations diverge (the volume fraction far
      outside [0, 1] after an advection, or a Courant number blown up at
      the step's end) is taken again from its start with half the step, up
      to maxStepRetakes times within any retakeWindow of simulated time
      (none in the start-up of a scene that iterates each step, retakeFrom),
      then the run stops with a FatalError naming the field and the time
      (createStepRetake.H, siloTime.H).
    - A static mesh; no MRF, no LTS.

    Incompressible, isothermal; the granular phase keeps a constant
    volume fraction (rho = rho_p), as in Zhou et al. 2019, section III.B.

\*---------------------------------------------------------------------------*/

#include "fvCFD.H"
#include "CMULES.H"
#include "EulerDdtScheme.H"
#include "localEulerDdtScheme.H"
#include "CrankNicolsonDdtScheme.H"
#include "subCycle.H"
#include "immiscibleIncompressibleTwoPhaseMixture.H"
#include "turbulentTransportModel.H"
#include "pimpleControl.H"
#include "fvOptions.H"
#include "fvcSmooth.H"
#include "fixedGradientFvPatchFields.H"
#include "fixedFluxPressureFvPatchScalarField.H"
#include "extrapolatedCalculatedFvPatchFields.H"
#include "muI.H"
#include "siloTime.H"

// * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * //

int main(int argc, char *argv[])
{
    argList::addNote
    (
        "Granular silo discharge: mu(I) granular phase (VOF) in air,"
        " incremental dt/rho projection."
    );

    #include "postProcess.H"

    #include "addCheckCaseOptions.H"
    #include "setRootCaseLists.H"
    #include "createSiloTime.H"
    #include "createMesh.H"
    #include "createControl.H"
    #include "createTimeControls.H"
    #include "initContinuityErrs.H"
    #include "createFields.H"
    #include "createAlphaFluxes.H"
    #include "createPorePressure.H"
    #include "faceReconstruction.H"
    #include "poreSupport.H"
    #include "createStepRetake.H"

    turbulence->validate();

    #include "CourantNo.H"
    #include "setInitialDeltaT.H"

    // * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * * //
    // The run ends once fewer grains than this are left (controlDict
    // stopGranularVolume, 0: never): the silo has emptied, and what would
    // follow (the last grains in the corners, air jetting through the
    // orifice) is no discharge
    const scalar stopGranularVolume
    (
        runTime.controlDict().get<scalar>("stopGranularVolume")
    );
    const bool stopWhenEmpty
    (
        stopGranularVolume > 0
     && gSum(alpha1.primitiveField()*mesh.V().field()) > stopGranularVolume
    );

    // A step taken again with half the stress share runs more outer
    // iterations (below): pimpleControl reads their count from the solution
    // dictionary at each loop. Looked up at each use, never kept: the runner
    // rewrites fvSolution during a run (a recovery's iterations put back) and
    // the dictionary is then read again. The count to put back at the next
    // step, -1: none
    auto pimpleDict = [&]() -> dictionary&
    {
        return static_cast<fvSolution&>(mesh).subDict("PIMPLE");
    };
    label outerCorrectorsToRestore = -1;

    Info<< "\nStarting time loop\n" << endl;

    while (runTime.run())
    {
        #include "readTimeControls.H"
        #include "CourantNo.H"
        #include "alphaCourantNo.H"
        #include "granularCourantNo.H"
        // The step at which the all-cell Courant number would be the
        // smoothing's, from this step's Courant number (createFields.H)
        const scalar courantSmoothingStep =
            faceSmoothingCourant/(CoNum + SMALL)*runTime.deltaTValue();
        #include "setDeltaT.H"
        faceSmoothingStep = runTime.deltaTValue();
        if (faceSmoothingByCourant)
        {
            faceSmoothingStep = max
            (
                min
                (
                    min(courantSmoothingStep, faceSmoothingMaxStep),
                    faceSmoothingMaxRatio*runTime.deltaTValue()
                ),
                runTime.deltaTValue()
            );
            Info<< "faceSmoothingStep = " << faceSmoothingStep << endl;
        }

        // The step, taken again from its start with half the step while
        // its outer iterations diverge (createStepRetake.H)
        saveStepStart();
        stressPressureDivergenceStep = stressPressureDivergence;
        // The scene's outer iterations back after a step taken again with
        // half the share, unless the dictionary was read again since (the
        // runner's own count)
        auto restoreOuterCorrectors = [&]()
        {
            if
            (
                outerCorrectorsToRestore > 0
             && pimpleDict().get<label>("nOuterCorrectors")
             == 4*outerCorrectorsToRestore
            )
            {
                pimpleDict().set("nOuterCorrectors", outerCorrectorsToRestore);
            }
            outerCorrectorsToRestore = -1;
        };
        restoreOuterCorrectors();
        // Whether this step has been taken again with half the share (once a step)
        bool shareRetaken = false;
        const siloTime::stepStart stepStart(runTime.start());
        // Back to the step's start: the fields, then the time
        auto backToStepStart = [&]()
        {
            restoreStepStart();
            runTime.rewind(stepStart);
        };
        // The end of this step's first pass, where it is taken again as a
        // check (createStepRetake.H)
        autoPtr<volVectorField> checkU;
        autoPtr<volScalarField> checkP_rgh;
        autoPtr<volScalarField> checkAlpha1;
        autoPtr<surfaceScalarField> checkPhi;
        const bool checkThisStep =
            retakeCheckInterval > 0
         && (runTime.timeIndex() + 1) % retakeCheckInterval == 0;
        for (;;)
        {
            ++runTime;

            Info<< "Time = " << runTime.timeName() << nl << endl;

            // Why the step failed (empty: it did not)
            string stepFailure;
            // The grains' velocity change of each outer iteration (rms), and
            // its largest, over the fastest grain's speed
            DynamicList<scalar> outerChange;
            DynamicList<scalar> outerMaxChange;

            // --- Pressure-velocity PIMPLE corrector loop
            while (pimple.loop())
            {
                if (!stepFailure.empty())
                {
                    continue;
                }

                // Each outer iteration's change of the grains' velocity: the
                // retake criteria use it and the log shows whether the
                // iterations converge (docs/solver.md)
                autoPtr<volVectorField> UOuterStart;
                if
                (
                    outerGrowthLimit > 0 || outerChangeLimit > 0
                 || pimple.nCorrPIMPLE() > 1
                )
                {
                    UOuterStart.reset(new volVectorField("UOuterStart", U));
                }

                #include "alphaControls.H"
                #include "alphaEqnSubCycle.H"

                {
                    const scalar alphaMin = gMin(alpha1.primitiveField());
                    const scalar alphaMax = gMax(alpha1.primitiveField());
                    if
                    (
                        !std::isfinite(alphaMin) || !std::isfinite(alphaMax)
                     || alphaMin < -retakeAlphaExcursion
                     || alphaMax > 1 + retakeAlphaExcursion
                    )
                    {
                        stepFailure =
                            "volume fraction " + alpha1.name() + " between "
                          + Foam::name(alphaMin) + " and " + Foam::name(alphaMax)
                          + " in outer iteration " + Foam::name(pimple.corr());
                        continue;
                    }
                }

                mixture.correct();

                #include "pfEqn.H"

                if (pimple.frozenFlow())
                {
                    continue;
                }

                #include "UEqn.H"

                // --- Pressure corrector loop
                while (pimple.correct())
                {
                    #include "pEqn.H"
                }

                if (pimple.turbCorr())
                {
                    turbulence->correct();
                }

                if (UOuterStart.valid())
                {
                    const scalarField grains(pos(alpha1.primitiveField() - 0.5));
                    const vectorField dU
                    (
                        U.primitiveField() - UOuterStart().primitiveField()
                    );
                    outerChange.append
                    (
                        Foam::sqrt
                        (
                            gSum(grains*mesh.V().field()*magSqr(dU))
                           /max(gSum(grains*mesh.V().field()), VSMALL)
                        )
                    );
                    outerMaxChange.append
                    (
                        gMax(grains*mag(dU))
                       /max(gMax(grains*mag(U.primitiveField())), VSMALL)
                    );
                    Info<< "Outer iteration " << pimple.corr()
                        << ": grains' velocity change rms "
                        << outerChange.last() << " m/s, largest "
                        << outerMaxChange.last()
                        << " of the fastest grain's speed" << endl;
                }
            }

            // The outer iterations diverging at the whole share: the step
            // again, at the same step, with half of it (createFields.H)
            if
            (
                stepFailure.empty() && implicitStressPressure
             && outerChange.size() >= 2
             && !shareRetaken
             && stepStart.value >= retakeFrom
             && stepStart.value >= shareRetakesFrom
            )
            {
                const label n = outerChange.size();
                const scalar growth =
                    outerChange[n - 1]/max(outerChange[n - 2], VSMALL);
                const scalar change = outerMaxChange[n - 1];
                if
                (
                    (outerGrowthLimit > 0 && growth > outerGrowthLimit)
                 || (outerChangeLimit > 0 && change > outerChangeLimit)
                )
                {
                    backToStepStart();
                    shareRetaken = true;
                    stressPressureDivergenceStep = 0.5*stressPressureDivergence;
                    // ... and with four times the outer iterations: three
                    // end a half-share step elsewhere than the whole share's
                    // steps around it, which can start a burst of its own
                    // (docs/solver.md)
                    outerCorrectorsToRestore =
                        pimpleDict().get<label>("nOuterCorrectors");
                    pimpleDict().set
                    (
                        "nOuterCorrectors", 4*outerCorrectorsToRestore
                    );
                    Info<< "Step retaken with half the stress share: outer"
                        << " iterations growing by " << growth << " (limit "
                        << outerGrowthLimit << "), the last moving a grain by "
                        << change << " of the fastest grain's speed (limit "
                        << outerChangeLimit << "), in the step from t = "
                        << stepStart.value << " with deltaT = "
                        << runTime.deltaTValue() << nl << endl;
                    continue;
                }
            }

            // The Courant number the step ends with (all cells, as
            // CourantNo.H): a blow-up in the last outer iteration
            if (stepFailure.empty() && maxCo > 0)
            {
                const scalar endCo =
                    0.5*gMax
                    (
                        fvc::surfaceSum(mag(phi))().primitiveField()
                       /mesh.V().field()
                    )*runTime.deltaTValue();
                if (!std::isfinite(endCo) || endCo > retakeCourantFactor*maxCo)
                {
                    stepFailure =
                        "Courant number " + Foam::name(endCo) + " (limit "
                      + Foam::name(maxCo) + ") at its end";
                }
            }

            if (checkThisStep && checkU.valid())
            {
                // The second pass of a checked step: it must end where the
                // first did
                // (a failed second pass differs by GREAT)
                const bool passed = stepFailure.empty();
                const scalar dU = passed ? gMax(mag(U - checkU())()) : GREAT;
                const scalar dP = passed ? gMax(mag(p_rgh - checkP_rgh())()) : GREAT;
                const scalar dAlpha =
                    passed ? gMax(mag(alpha1 - checkAlpha1())()) : GREAT;
                const scalar dPhi = passed ? gMax(mag(phi - checkPhi())()) : GREAT;
                Info<< "Retake check in the step from t = " << stepStart.value
                    << ": largest differences U " << dU << ", p_rgh " << dP
                    << ", alpha " << dAlpha << ", phi " << dPhi << nl << endl;
                if (dU != 0 || dP != 0 || dAlpha != 0 || dPhi != 0)
                {
                    FatalErrorInFunction
                        << "Retake check failed: the step from t = "
                        << stepStart.value << " taken again from its saved"
                        << " start does not end on the same fields (U by "
                        << dU << ", p_rgh by " << dP << ", alpha by " << dAlpha
                        << ", phi by " << dPhi << "): a field the step"
                        << " carries over is not put back"
                        << " (createStepRetake.H)" << exit(FatalError);
                }
                break;
            }

            if (stepFailure.empty() && checkThisStep)
            {
                checkU.reset(new volVectorField("checkU", U));
                checkP_rgh.reset(new volScalarField("checkP_rgh", p_rgh));
                checkAlpha1.reset(new volScalarField("checkAlpha1", alpha1));
                checkPhi.reset(new surfaceScalarField("checkPhi", phi));
                backToStepStart();
                Info<< "Step retaken for a check: in the step from t = "
                    << stepStart.value << " with deltaT = "
                    << runTime.deltaTValue() << nl << endl;
                continue;
            }

            if (stepFailure.empty())
            {
                break;
            }

            const scalar failedDeltaT = runTime.deltaTValue();
            // A step taken again with half the share that fails is taken as
            // the whole share first took it (that pass passed, and a retake
            // starts from the same state): at half the share the longer
            // iteration can diverge where three passes at the whole share
            // do not (docs/solver.md)
            if (stressPressureDivergenceStep != stressPressureDivergence)
            {
                backToStepStart();
                stressPressureDivergenceStep = stressPressureDivergence;
                restoreOuterCorrectors();
                Info<< "Step retaken at the whole stress share: the step taken"
                    << " again with half of it failed (" << stepFailure.c_str()
                    << "), in the step from t = " << stepStart.value
                    << " with deltaT = " << failedDeltaT << nl << endl;
                shareRetakesFrom = stepStart.value + retakeWindow;
                Info<< "No step taken again at half the stress share before"
                    << " t = " << shareRetakesFrom << " (one retakeWindow"
                    << " after the step that failed at it)" << nl << endl;
                continue;
            }
            if (stepStart.value < retakeFrom)
            {
                FatalErrorInFunction
                    << "Step diverged: " << stepFailure.c_str()
                    << ", in the step from t = " << stepStart.value
                    << " with deltaT = " << failedDeltaT << ", in the start-up"
                    << " (no retake before t = " << retakeFrom << ")"
                    << exit(FatalError);
            }
            // the retakes of the last retakeWindow, this step's included
            {
                label kept = 0;
                forAll(retakeTimes, i)
                {
                    if (retakeTimes[i] > stepStart.value - retakeWindow)
                    {
                        retakeTimes[kept++] = retakeTimes[i];
                    }
                }
                retakeTimes.setSize(kept);
            }
            if (retakeTimes.size() >= maxStepRetakes)
            {
                FatalErrorInFunction
                    << "Step diverged: " << stepFailure.c_str()
                    << ", in the step from t = " << stepStart.value
                    << " with deltaT = " << failedDeltaT << ", after "
                    << retakeTimes.size() << " retakes since t = "
                    << (retakeTimes.empty() ? stepStart.value : retakeTimes[0])
                    << " (at most " << maxStepRetakes << " within "
                    << retakeWindow << " s)"
                    << exit(FatalError);
            }
            retakeTimes.append(stepStart.value);

            backToStepStart();
            runTime.setDeltaT(0.5*failedDeltaT);
            if (!faceSmoothingByCourant)
            {
                faceSmoothingStep = runTime.deltaTValue();
            }
            Info<< "Step retaken (" << retakeTimes.size() << " of " << maxStepRetakes
                << "): " << stepFailure.c_str() << ", in the step from t = "
                << stepStart.value << " with deltaT = " << failedDeltaT
                << "; taken again with deltaT = " << runTime.deltaTValue()
                << nl << endl;
        }

        const scalar granularVolume =
            stopWhenEmpty
          ? gSum(alpha1.primitiveField()*mesh.V().field())
          : GREAT;
        if (granularVolume < stopGranularVolume)
        {
            Info<< "The silo has emptied: granular volume " << granularVolume
                << " m3 below " << stopGranularVolume << " m3 at t = "
                << runTime.timeName() << nl << endl;
            runTime.writeAndEnd();
        }
        else
        {
            runTime.write();
        }

        runTime.printExecutionTime(Info);
    }

    Info<< "End\n" << endl;

    return 0;
}


// ************************************************************************* //
