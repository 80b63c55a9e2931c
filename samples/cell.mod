MODULE CellMain
  !
  ! Machine tending cell: pick a blank from the infeed conveyor, load the
  ! lathe, unload the finished part onto the outfeed table.
  ! Robot: IRB 1600-10/1.45, gripper on tool flange, two work objects.
  !
  PERS tooldata tGripper:=[TRUE,[[0,0,182.5],[1,0,0,0]],[2.4,[0,0,65],[1,0,0,0],0.011,0.012,0.006]];
  PERS tooldata tProbe:=[TRUE,[[31.2,0,145.8],[0.9238795,0,0.3826834,0]],[0.6,[5,0,50],[1,0,0,0],0,0,0]];
  PERS wobjdata wInfeed:=[FALSE,TRUE,"",[[820,-410,312],[0.7071068,0,0,0.7071068]],[[0,0,0],[1,0,0,0]]];
  PERS wobjdata wLathe:=[FALSE,TRUE,"",[[955.5,380,702.25],[1,0,0,0]],[[0,0,12.5],[1,0,0,0]]];
  PERS loaddata lBlank:=[1.8,[0,0,40],[1,0,0,0],0,0,0];
  CONST speeddata vApproach:=[400,150,5000,1000];
  CONST zonedata zPick:=[FALSE,2,3,3,0.3,3,0.3];

  CONST jointtarget jHome:=[[0,-20,30,0,80,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
  CONST robtarget pInfeedAbove:=[[120,85,150],[0,0,1,0],[-1,0,-2,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
  CONST robtarget pInfeedPick:=[[120,85,0],[0,0,1,0],[-1,0,-2,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
  CONST robtarget pChuck:=[[0,0,0],[0.5,-0.5,0.5,0.5],[0,-1,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
  CONST robtarget pChuckOut:=[[-180,0,0],[0.5,-0.5,0.5,0.5],[0,-1,0,1],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
  PERS robtarget pOutfeed:=[[610.5,-520,402],[0,0.7071068,0.7071068,0],[-1,-1,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]];
  VAR robtarget pCurrent;
  VAR num nParts:=0;

  PROC main()
    MoveAbsJ jHome\NoEOffs, v1000, z50, tGripper;
    WHILE nParts < 100 DO
      PickBlank;
      LoadLathe;
      nParts := nParts + 1;
    ENDWHILE
    MoveAbsJ jHome, v1000, fine, tGripper;
  ENDPROC

  PROC PickBlank()
    MoveJ pInfeedAbove, v1500, z20, tGripper\WObj:=wInfeed;
    MoveL pInfeedPick, vApproach, fine, tGripper\WObj:=wInfeed;
    Set doGripClose;
    WaitTime 0.3;
    GripLoad lBlank;
    MoveL pInfeedAbove, v500, zPick, tGripper\WObj:=wInfeed;
  ENDPROC

  PROC LoadLathe()
    MoveJ pChuckOut, v1000, z10, tGripper\WObj:=wLathe;
    MoveL pChuck, v100, fine, tGripper\WObj:=wLathe;
    Reset doGripClose;
    WaitTime \InPos, 0.2;
    GripLoad load0;
    MoveL pChuckOut, v300, z5, tGripper\WObj:=wLathe;
    pCurrent := CRobT(\Tool:=tGripper \WObj:=wobj0);
    MoveL Offs(pCurrent, 0, 0, 100), v500, z50, tGripper;
    MoveJ pOutfeed, v1500, z50, tGripper\V:=1800;
  ENDPROC
ENDMODULE
